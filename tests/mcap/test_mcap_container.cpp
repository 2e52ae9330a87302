// SPDX-License-Identifier: Apache-2.0
// The MCAP writer and reader: what one writes the other reads back exactly, with its schemas,
// channels, statistics and summary; damaged files (cut short, bad CRC, wrong magic, absurd
// lengths) give one sentence and every intact message.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "mcap_test_files.hpp"
#include "sim/mcap/reader.hpp"
#include "sim/mcap/writer.hpp"

namespace {

using sim::mcap::Compression;
using sim::testing::TempFile;

struct Sent {
  sim::mcap::MessageHeader header;
  std::vector<std::byte> data;
};

// Two channels; messages of varied sizes (some larger than a chunk) with distinct contents.
std::vector<Sent> make_messages(std::size_t count) {
  std::vector<Sent> out;
  for (std::size_t i = 0; i < count; ++i) {
    Sent s;
    s.header.channel_id = static_cast<std::uint16_t>(1 + i % 2);
    s.header.sequence = static_cast<std::uint32_t>(i / 2);
    s.header.log_time = 1'700'000'000'000'000'000ull + i * 1'000'000;
    s.header.publish_time = s.header.log_time - 500;
    const std::size_t size = (i % 7 == 0) ? 300'000 + i : 100 + 37 * i;
    s.data.resize(size);
    for (std::size_t k = 0; k < size; ++k) s.data[k] = static_cast<std::byte>((k * 31 + i * 7) & 0xff);
    std::memcpy(s.data.data(), &i, sizeof i);  // makes every message's start unique in the file
    out.push_back(std::move(s));
  }
  return out;
}

void write_file(const std::string& path, const std::vector<Sent>& messages, Compression compression,
                std::uint64_t chunk_size = 64 * 1024) {
  sim::mcap::WriterOptions options;
  options.compression = compression;
  options.chunk_size = chunk_size;
  auto writer = sim::mcap::Writer::create(path, options);
  ASSERT_TRUE(writer) << writer.error().message;
  const auto cloud = writer->add_schema("sensor_msgs/msg/PointCloud2", "ros2msg", "uint32 height\n");
  const auto image = writer->add_schema("sensor_msgs/msg/Image", "ros2msg", "uint32 width\n");
  EXPECT_EQ(writer->add_channel(cloud, "/lidar_top", "cdr", {{"sim.kind", "points"}}), 1);
  EXPECT_EQ(writer->add_channel(image, "/camera_front", "cdr", {{"sim.kind", "image"}}), 2);
  for (const auto& m : messages) {
    ASSERT_FALSE(writer->write(m.header, m.data));
  }
  ASSERT_FALSE(writer->close());
}

std::vector<Sent> read_all(sim::mcap::Reader& reader) {
  std::vector<Sent> out;
  while (auto m = reader.next()) out.push_back({m->header, {m->data.begin(), m->data.end()}});
  return out;
}

void expect_same(const Sent& got, const Sent& want) {
  EXPECT_EQ(got.header.channel_id, want.header.channel_id);
  EXPECT_EQ(got.header.sequence, want.header.sequence);
  EXPECT_EQ(got.header.log_time, want.header.log_time);
  EXPECT_EQ(got.header.publish_time, want.header.publish_time);
  EXPECT_TRUE(got.data == want.data) << "message " << want.header.sequence << " differs";
}

class EveryCompression : public ::testing::TestWithParam<Compression> {};

TEST_P(EveryCompression, ReadsBackEveryMessageSchemaChannelAndTheSummary) {
  TempFile file;
  const auto sent = make_messages(60);
  write_file(file.path(), sent, GetParam());
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ(reader->problem(), "");
  EXPECT_TRUE(reader->has_summary());
  EXPECT_EQ(reader->profile(), "ros2");
  ASSERT_EQ(reader->schemas().size(), 2u);
  EXPECT_EQ(reader->schemas().at(1).name, "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(reader->schemas().at(2).encoding, "ros2msg");
  EXPECT_EQ(reader->schemas().at(2).data, "uint32 width\n");
  ASSERT_EQ(reader->channels().size(), 2u);
  EXPECT_EQ(reader->channels().at(1).topic, "/lidar_top");
  EXPECT_EQ(reader->channels().at(2).message_encoding, "cdr");
  EXPECT_EQ(reader->channels().at(2).metadata.at("sim.kind"), "image");
  ASSERT_TRUE(reader->statistics());
  EXPECT_EQ(reader->statistics()->message_count, 60u);
  EXPECT_EQ(reader->statistics()->channel_message_counts.at(1), 30u);
  EXPECT_EQ(reader->statistics()->message_start_time, sent.front().header.log_time);
  EXPECT_EQ(reader->statistics()->message_end_time, sent.back().header.log_time);
  EXPECT_GT(reader->statistics()->chunk_count, 5u);

  const auto got = read_all(*reader);
  ASSERT_EQ(got.size(), sent.size());
  for (std::size_t i = 0; i < got.size(); ++i) expect_same(got[i], sent[i]);
  EXPECT_EQ(reader->problem(), "");

  reader->rewind();
  EXPECT_EQ(read_all(*reader).size(), sent.size());
}

INSTANTIATE_TEST_SUITE_P(Mcap, EveryCompression,
                         ::testing::Values(Compression::none, Compression::lz4, Compression::zstd),
                         [](const auto& param_info) {
                           return param_info.param == Compression::none ? std::string("none")
                                                                  : std::string(to_string(param_info.param));
                         });

TEST(McapReader, DeliversTheMessagesOfAChunkInLogTimeOrder) {
  TempFile file;
  auto sent = make_messages(6);
  std::swap(sent[1].header.log_time, sent[4].header.log_time);
  write_file(file.path(), sent, Compression::zstd, 1u << 24);  // one chunk
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  const auto got = read_all(*reader);
  ASSERT_EQ(got.size(), 6u);
  for (std::size_t i = 1; i < got.size(); ++i) {
    EXPECT_LE(got[i - 1].header.log_time, got[i].header.log_time);
  }
}

TEST(McapReader, ReadsEveryWholeChunkOfATruncatedFileAndSaysItWasCutShort) {
  TempFile file;
  const auto sent = make_messages(60);
  write_file(file.path(), sent, Compression::lz4);
  auto bytes = sim::testing::read_bytes(file.path());
  bytes.resize(bytes.size() * 6 / 10);  // somewhere in the data section
  sim::testing::write_bytes(file.path(), bytes);

  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_FALSE(reader->has_summary());
  EXPECT_NE(reader->problem().find("cut short"), std::string::npos) << reader->problem();
  EXPECT_EQ(reader->channels().size(), 2u);  // found in the data section
  const auto got = read_all(*reader);
  EXPECT_GT(got.size(), 10u);
  EXPECT_LT(got.size(), sent.size());
  for (std::size_t i = 0; i < got.size(); ++i) expect_same(got[i], sent[i]);
}

TEST(McapReader, SkipsAChunkThatFailsItsCrcAndDeliversTheOthers) {
  TempFile file;
  const auto sent = make_messages(40);
  write_file(file.path(), sent, Compression::none);
  auto bytes = sim::testing::read_bytes(file.path());
  // Flip a byte of the payload of message 20 (its pattern is unique in the file).
  const auto& victim = sent[20].data;
  const auto it = std::search(bytes.begin(), bytes.end(), victim.begin(), victim.begin() + 64);
  ASSERT_NE(it, bytes.end());
  *(it + 10) ^= std::byte{0x55};
  sim::testing::write_bytes(file.path(), bytes);

  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  const auto got = read_all(*reader);
  EXPECT_NE(reader->problem().find("CRC"), std::string::npos) << reader->problem();
  EXPECT_EQ(reader->skipped_chunks(), 1u);
  EXPECT_LT(got.size(), sent.size());
  EXPECT_GT(got.size(), sent.size() / 2);
  for (const auto& g : got) {
    expect_same(g, sent[g.header.sequence * 2 + (g.header.channel_id - 1)]);
    EXPECT_NE(g.header.log_time, sent[20].header.log_time);
  }
}

TEST(McapReader, RefusesAFileWithTheWrongMagicInOneSentence) {
  TempFile file;
  write_file(file.path(), make_messages(4), Compression::zstd);
  auto bytes = sim::testing::read_bytes(file.path());
  bytes[1] = std::byte{'X'};
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("not an MCAP"), std::string::npos);
  EXPECT_EQ(reader.error().message.find('\n'), std::string::npos);
}

TEST(McapReader, StopsAtARecordWithAnAbsurdLength) {
  TempFile file;
  const auto sent = make_messages(30);
  write_file(file.path(), sent, Compression::zstd);
  auto bytes = sim::testing::read_bytes(file.path());
  // The second chunk record: find the chunk opcode after the first chunk, make its length huge.
  auto reader0 = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader0);
  std::size_t pos = 8;
  int chunks = 0;
  while (pos + 9 < bytes.size()) {
    std::uint64_t length;
    std::memcpy(&length, bytes.data() + pos + 1, 8);
    if (bytes[pos] == std::byte{0x06} && ++chunks == 2) {
      const std::uint64_t absurd = ~std::uint64_t{0} - 3;
      std::memcpy(bytes.data() + pos + 1, &absurd, 8);
      break;
    }
    pos += 9 + length;
  }
  ASSERT_EQ(chunks, 2);
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  const auto got = read_all(*reader);
  EXPECT_FALSE(got.empty());
  EXPECT_LT(got.size(), sent.size());
  EXPECT_NE(reader->problem().find("claims"), std::string::npos) << reader->problem();
}

TEST(McapReader, ReadsTheDataSectionWhenTheSummaryIsDamaged) {
  TempFile file;
  const auto sent = make_messages(20);
  write_file(file.path(), sent, Compression::lz4);
  auto bytes = sim::testing::read_bytes(file.path());
  std::uint64_t summary_start;
  std::memcpy(&summary_start, bytes.data() + bytes.size() - 8 - 20, 8);
  bytes[summary_start + 12] ^= std::byte{1};
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  EXPECT_FALSE(reader->has_summary());
  EXPECT_NE(reader->problem().find("summary"), std::string::npos) << reader->problem();
  EXPECT_EQ(reader->channels().size(), 2u);
  EXPECT_EQ(read_all(*reader).size(), sent.size());
}

// Files of other writers may leave the Schema and Channel copies out of the summary (Go's
// SkipRepeatedChannelInfos, Python's repeat_channels=False): the channels are in the data section.
struct SummaryCopies {
  bool schemas;
  bool channels;
};
class SummaryWithout : public ::testing::TestWithParam<SummaryCopies> {};

TEST_P(SummaryWithout, TheChannelsAndSchemasAreReadFromTheDataSection) {
  TempFile file;
  const auto sent = make_messages(12);
  {
    sim::mcap::WriterOptions options;
    options.repeat_schemas = GetParam().schemas;
    options.repeat_channels = GetParam().channels;
    auto writer = sim::mcap::Writer::create(file.path(), options);
    ASSERT_TRUE(writer);
    const auto cloud = writer->add_schema("sensor_msgs/msg/PointCloud2", "ros2msg", "uint32 height\n");
    const auto image = writer->add_schema("sensor_msgs/msg/Image", "ros2msg", "uint32 width\n");
    writer->add_channel(cloud, "/lidar_top", "cdr", {{"sim.kind", "points"}});
    writer->add_channel(image, "/camera_front", "cdr", {{"sim.kind", "image"}});
    for (const auto& m : sent) ASSERT_FALSE(writer->write(m.header, m.data));
    ASSERT_FALSE(writer->close());
  }
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  EXPECT_TRUE(reader->has_summary());
  ASSERT_EQ(reader->channels().size(), 2u);
  const auto* schema = reader->schema_of(reader->channels().at(2));
  ASSERT_NE(schema, nullptr);
  EXPECT_EQ(schema->name, "sensor_msgs/msg/Image");
  EXPECT_EQ(reader->channels().at(1).topic, "/lidar_top");
  EXPECT_EQ(read_all(*reader).size(), sent.size());
  EXPECT_EQ(reader->problem(), "");
}

INSTANTIATE_TEST_SUITE_P(Mcap, SummaryWithout,
                         ::testing::Values(SummaryCopies{false, false}, SummaryCopies{true, false},
                                           SummaryCopies{false, true}));

// Where the Schema record is in a file write_file made: after the magic and the Header.
std::size_t schema_record_offset(const std::vector<std::byte>& bytes) {
  std::uint64_t header_length;
  std::memcpy(&header_length, bytes.data() + 9, 8);
  return 8 + 9 + header_length;
}

TEST(McapReader, AFooterInsideTheDataSectionIsDamageThatIsSaidAndReadAround) {
  TempFile file;
  const auto sent = make_messages(10);
  write_file(file.path(), sent, Compression::zstd);
  auto bytes = sim::testing::read_bytes(file.path());
  const std::size_t at = schema_record_offset(bytes);
  ASSERT_EQ(bytes[at], std::byte{0x03});
  bytes[at] = std::byte{0x02};  // one flipped bit: the Schema record reads as a Footer
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  EXPECT_EQ(read_all(*reader).size(), sent.size());  // the summary still has the schema
  EXPECT_NE(reader->problem().find("Footer record at byte " + std::to_string(at)), std::string::npos)
      << reader->problem();
}

TEST(McapReader, SaysWhenTheDataEndRecordIsMissing) {
  TempFile file;
  write_file(file.path(), make_messages(6), Compression::lz4);
  auto bytes = sim::testing::read_bytes(file.path());
  std::uint64_t summary_start;
  std::memcpy(&summary_start, bytes.data() + bytes.size() - 8 - 20, 8);
  const std::size_t data_end = summary_start - 13;  // opcode, length 4, the CRC
  ASSERT_EQ(bytes[data_end], std::byte{0x0F});
  bytes[data_end] = std::byte{0x1F};  // an unknown opcode, skipped as the spec says
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  EXPECT_EQ(read_all(*reader).size(), 6u);
  EXPECT_NE(reader->problem().find("without its Data End record"), std::string::npos) << reader->problem();
}

TEST(McapReader, SaysWhenTheFileHoldsFewerMessagesThanItsSummaryCounts) {
  TempFile file;
  const auto sent = make_messages(20);
  {
    sim::mcap::WriterOptions options;
    options.crc = false;  // no CRC gives the damage away: only the count can
    options.compression = Compression::none;
    options.chunk_size = 1024;
    auto writer = sim::mcap::Writer::create(file.path(), options);
    ASSERT_TRUE(writer);
    writer->add_channel(writer->add_schema("s", "ros2msg", ""), "/a", "cdr", {});
    writer->add_channel(1, "/b", "cdr", {});
    for (const auto& m : sent) ASSERT_FALSE(writer->write(m.header, m.data));
    ASSERT_FALSE(writer->close());
  }
  auto bytes = sim::testing::read_bytes(file.path());
  std::size_t pos = schema_record_offset(bytes);
  while (bytes[pos] != std::byte{0x06}) {  // the first chunk
    std::uint64_t length;
    std::memcpy(&length, bytes.data() + pos + 1, 8);
    pos += 9 + length;
  }
  bytes[pos] = std::byte{0x46};  // now an unknown record, skipped
  sim::testing::write_bytes(file.path(), bytes);
  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader);
  const auto got = read_all(*reader);
  EXPECT_LT(got.size(), sent.size());
  EXPECT_NE(reader->problem().find("the summary counts 20 messages but only " + std::to_string(got.size())),
            std::string::npos)
      << reader->problem();
}

std::vector<std::byte> payload(std::uint8_t value) { return std::vector<std::byte>(8, std::byte{value}); }

TEST(McapReader, SaysWhenAChannelIdIsRedefinedOrAMessageHasNoChannel) {
  sim::testing::RawMcap raw;
  raw.schema(1, "sensor_msgs/msg/Image", "").channel(1, 1, "/first").message(1, 0, 10, payload(1));
  raw.channel(1, 1, "/second").message(1, 1, 20, payload(2)).message(9, 2, 30, payload(3));
  const auto bytes = raw.finish();
  auto reader = sim::mcap::Reader::from_bytes(bytes);
  ASSERT_TRUE(reader);
  const auto got = read_all(*reader);
  ASSERT_EQ(got.size(), 2u);  // the one on channel 9 is not delivered
  EXPECT_EQ(reader->channels().at(1).topic, "/first");
  EXPECT_NE(reader->problem().find("redefines channel id 1 (topic /second)"), std::string::npos)
      << reader->problem();
  EXPECT_EQ(reader->problem_count(), 2u);
}

TEST(McapReader, SaysWhenAChunkHoldsAChunk) {
  using Raw = sim::testing::RawMcap;
  const auto message = Raw::encode(0x05, Raw::message_fields(1, 0, 10, payload(1)));
  Raw inner_file;
  inner_file.chunk(message);
  // The inner chunk record is what follows the magic and the Header in inner_file.
  const auto& inner_bytes = inner_file.bytes();
  std::uint64_t header_length;
  std::memcpy(&header_length, inner_bytes.data() + 9, 8);
  const std::vector<std::byte> inner(inner_bytes.begin() + static_cast<std::ptrdiff_t>(8 + 9 + header_length),
                                     inner_bytes.end());
  Raw raw;
  raw.schema(1, "sensor_msgs/msg/Image", "").channel(1, 1, "/a").chunk(inner).message(1, 1, 20, payload(2));
  const auto bytes = raw.finish();
  auto reader = sim::mcap::Reader::from_bytes(bytes);
  ASSERT_TRUE(reader);
  EXPECT_EQ(read_all(*reader).size(), 1u);
  EXPECT_NE(reader->problem().find("holds another chunk"), std::string::npos) << reader->problem();
}

TEST(McapReader, RefusesAFifoWithoutWaitingForAWriter) {
  TempFile fifo(".fifo");
  ASSERT_EQ(::mkfifo(fifo.path().c_str(), 0600), 0);
  auto reader = sim::mcap::Reader::open(fifo.path());  // blocked forever in open() before
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("not a regular file"), std::string::npos) << reader.error().message;
}

TEST(McapWriter, RefusesAFifoWithoutWaitingForAReader) {
  TempFile fifo(".fifo");
  ASSERT_EQ(::mkfifo(fifo.path().c_str(), 0600), 0);
  auto writer = sim::mcap::Writer::create(fifo.path());
  ASSERT_FALSE(writer);
  EXPECT_NE(writer.error().message.find("FIFO"), std::string::npos) << writer.error().message;
}

TEST(McapWriter, CountsAsStoredOnlyTheMessagesOfChunksThatReachedTheFile) {
  sim::mcap::WriterOptions options;
  options.chunk_size = 1024;
  auto writer = sim::mcap::Writer::create("/dev/full", options);
  ASSERT_TRUE(writer);  // the header is still buffered
  writer->add_channel(writer->add_schema("s", "ros2msg", ""), "/a", "cdr", {});
  const auto sent = make_messages(3);
  EXPECT_TRUE(writer->write({1, 0, 1, 1}, sent[0].data));  // a whole chunk: written, fails
  EXPECT_TRUE(writer->close());
  EXPECT_EQ(writer->stored(1).messages, 0u);
  EXPECT_EQ(writer->bytes_written(), 0u);
}

TEST(McapText, FileStringsCannotSendControlSequencesToATerminal) {
  EXPECT_EQ(sim::mcap::printable("/cam\x1b]0;owned\x07"), "/cam\\x1b]0;owned\\x07");
  EXPECT_EQ(sim::mcap::printable("z\xfftd"), "z\\xfftd");
  EXPECT_EQ(sim::mcap::printable("\xc2\x9b" "2J"), "\\xc2\\x9b2J");  // C1 CSI in UTF-8
  EXPECT_EQ(sim::mcap::printable("caméra/front"), "caméra/front");  // UTF-8 letters stay
}

TEST(McapWriter, SaysWhyItCannotCreateAFile) {
  auto writer = sim::mcap::Writer::create("/nonexistent-dir/x.mcap");
  ASSERT_FALSE(writer);
  EXPECT_NE(writer.error().message.find("/nonexistent-dir/x.mcap"), std::string::npos);
}

}  // namespace
