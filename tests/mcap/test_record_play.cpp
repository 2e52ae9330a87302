// SPDX-License-Identifier: Apache-2.0
// sim_record and sim_play as real processes: a camera (mcap_test_camera) and the Pandar64
// capture (sim_replay_pcap) are recorded; the file holds every frame byte for byte with its
// stamps; sim_play puts them back into SIM streams that readers cannot tell from the originals.
// Damaged recordings play as far as they are intact and say what was wrong; JPEG CompressedImage
// files without SIM metadata play too.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <turbojpeg.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

#include "../../sim/region.hpp"
#include "channel_player.hpp"
#include "mcap_test_files.hpp"
#include "record_play_support.hpp"
#include "sim/mcap/writer.hpp"
#include "sim/writer.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"
#include "sim_test/process.hpp"
#include "test_frames.hpp"

namespace {

using sim::testing::FrameCollector;
using sim::testing::kCameraFrames;
using sim::testing::kHeight;
using sim::testing::kWidth;
using sim::testing::Process;
using sim::testing::Recording;
using sim::testing::unique_stream;
using sim::testing::json_number;
using sim::testing::record;

class RecordAndPlay : public ::testing::TestWithParam<std::string> {};

TEST_P(RecordAndPlay, EveryRecordedFrameComesBackByteForByteWithItsStamps) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const Recording rec = record(file.path(), GetParam(), cleanup);

  // The file: every camera frame that was not reported missed, exactly as written.
  auto recorded = sim::testing::read_recording(file.path());
  const auto& camera = recorded[rec.camera];
  const auto& lidar = recorded[rec.lidar];
  const std::uint64_t camera_missed = json_number(rec.json, rec.camera, "missed");
  ASSERT_NE(camera_missed, UINT64_MAX) << rec.json;
  EXPECT_EQ(camera.size() + camera_missed, kCameraFrames) << rec.json;
  EXPECT_EQ(json_number(rec.json, rec.camera, "frames"), camera.size());
  ASSERT_FALSE(camera.empty());
  for (const auto& m : camera) {
    const std::uint64_t index = m.sequence - 1;  // the camera's first frame is seq 1
    std::vector<std::byte> expected(std::size_t{kWidth} * 3 * kHeight);
    sim::testing::fill_test_image(expected, kWidth * 3, kHeight, index);
    EXPECT_TRUE(m.frame == expected) << "camera frame " << m.sequence << " differs";
    EXPECT_EQ(m.header_stamp_ns, sim::testing::test_image_stamp(index));
    EXPECT_EQ(static_cast<std::int64_t>(m.publish_time), sim::testing::test_image_stamp(index));
  }
  // LiDAR frames equal the frames a live reader saw with the same sequence number.
  ASSERT_FALSE(lidar.empty()) << rec.json;
  std::size_t compared = 0;
  for (const auto& m : lidar) {
    for (const auto& f : rec.live_lidar) {
      if (f.seq != m.sequence) continue;
      EXPECT_TRUE(m.frame == f.bytes) << "lidar frame " << m.sequence << " differs";
      EXPECT_EQ(m.header_stamp_ns, f.stamp_ns);
      EXPECT_EQ(static_cast<std::int64_t>(m.publish_time), f.stamp_ns);
      ++compared;
    }
  }
  EXPECT_GT(compared, 0u) << "no recorded LiDAR frame was also seen live";

  // Playback into new streams: the same bytes, stamps and layouts, in order.
  const std::string camera_out = unique_stream("cam_play");
  const std::string lidar_out = unique_stream("lidar_play");
  cleanup.names.insert(cleanup.names.end(), {camera_out, lidar_out});
  FrameCollector played_camera(camera_out);
  FrameCollector played_lidar(lidar_out);
  Process player({SIM_PLAY, file.path(), "--remap", rec.camera + "=" + camera_out, "--remap",
                  rec.lidar + "=" + lidar_out, "--wait-for-readers", "--rate", "2"});
  EXPECT_EQ(player.wait(), 0) << player.err();
  played_camera.wait_for(camera.size());
  played_lidar.wait_for(lidar.size());
  played_camera.stop();
  played_lidar.stop();

  auto check = [](const std::vector<sim::testing::Recorded>& want, FrameCollector& got_from,
                  const sim::Layout& layout, const char* what) {
    const auto got = got_from.frames();
    EXPECT_FALSE(got.empty()) << what;
    EXPECT_EQ(got.size() + got_from.skipped(), want.size()) << what;
    for (const auto& f : got) {
      ASSERT_LE(f.seq, want.size()) << what;
      const auto& m = want[f.seq - 1];  // a new stream: the k-th frame played is seq k
      EXPECT_TRUE(f.bytes == m.frame) << what << " frame " << f.seq << " differs";
      EXPECT_EQ(f.stamp_ns, m.header_stamp_ns) << what;
      EXPECT_EQ(f.layout, layout) << what << ": " << f.layout.describe();
    }
  };
  check(camera, played_camera,
        sim::Layout::of(sim::ImageLayout::packed(kWidth, kHeight, sim::PixelFormat::bgr8)), "camera");
  ASSERT_FALSE(rec.live_lidar.empty());
  check(lidar, played_lidar, rec.live_lidar.front().layout, "lidar");
}

INSTANTIATE_TEST_SUITE_P(Mcap, RecordAndPlay, ::testing::Values("zstd", "lz4", "none"));

TEST(SimPlay, PlaysTheIntactPartOfATruncatedRecordingAndSaysSo) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const Recording rec = record(file.path(), "lz4", cleanup);
  const auto full = sim::testing::read_recording(file.path());
  const std::size_t camera_frames = full.at(rec.camera).size();

  auto bytes = sim::testing::read_bytes(file.path());
  bytes.resize(bytes.size() / 2);
  sim::testing::write_bytes(file.path(), bytes);
  const std::size_t intact = sim::testing::read_recording(file.path())[rec.camera].size();
  ASSERT_LT(intact, camera_frames);

  const std::string camera_out = unique_stream("cam_cut");
  const std::string lidar_out = unique_stream("lidar_cut");
  cleanup.names.insert(cleanup.names.end(), {camera_out, lidar_out});
  FrameCollector played(camera_out);
  Process player({SIM_PLAY, file.path(), "--remap", rec.camera + "=" + camera_out, "--remap",
                  rec.lidar + "=" + lidar_out, "--max-rate"});
  EXPECT_EQ(player.wait(), 1);
  EXPECT_NE(player.err().find("cut short"), std::string::npos) << player.err();
  played.wait_for(intact, std::chrono::seconds(5));
  played.stop();
  // Unpaced, a reader may skip frames; what it got is the intact start of the recording.
  for (const auto& f : played.frames()) EXPECT_LE(f.seq, intact);
}

TEST(SimPlay, RefusesAFileThatIsNotMcapInOneSentence) {
  sim::testing::TempFile file;
  sim::testing::write_bytes(file.path(), std::vector<std::byte>(100, std::byte{'x'}));
  const auto result = sim::testing::run({SIM_PLAY, file.path()});
  EXPECT_EQ(result.code, 1);
  EXPECT_NE(result.err.find("not an MCAP"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

TEST(SimRecord, RefusesAStreamThatDoesNotExistInOneSentence) {
  sim::testing::TempFile file;
  const auto result = sim::testing::run({SIM_RECORD, "-o", file.path(), unique_stream("absent")});
  EXPECT_EQ(result.code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

TEST(SimRecord, AnswersAWrongCommandLineWithExitCode2) {
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "/x"}).code, 2);                        // no -o
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "-o", "x.mcap", "--all", "/x"}).code, 2);
  EXPECT_EQ(sim::testing::run({SIM_PLAY, "x.mcap", "--remap", "nonsense"}).code, 2);
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "--help"}).code, 0);
  EXPECT_EQ(sim::testing::run({SIM_PLAY, "--help"}).code, 0);
}

}  // namespace

namespace {

// A 64x48 JPEG whose pixels follow from `index`.
std::vector<std::byte> make_jpeg(std::uint64_t index) {
  std::vector<unsigned char> rgb(64 * 48 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>((i / 3 + index * 40) & 0xff);
  tjhandle handle = tjInitCompress();
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  tjCompress2(handle, rgb.data(), 64, 0, 48, TJPF_RGB, &jpeg, &size, TJSAMP_420, 90, 0);
  std::vector<std::byte> out(reinterpret_cast<std::byte*>(jpeg), reinterpret_cast<std::byte*>(jpeg) + size);
  tjFree(jpeg);
  tjDestroy(handle);
  return out;
}

TEST(SimPlay, PlaysJpegCompressedImagesOfAFileWithoutSimMetadata) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  std::vector<std::vector<std::byte>> jpegs;
  {
    auto writer = sim::mcap::Writer::create(file.path());
    ASSERT_TRUE(writer);
    const auto type = sim::ros2::MessageType::compressed_image;
    const auto schema = writer->add_schema(sim::ros2::ros_type_name(type), "ros2msg",
                                           sim::ros2::ros2msg_schema(type));
    const auto channel = writer->add_channel(schema, "/front_jpeg", "cdr", {{"offered_qos_profiles", ""}});
    for (std::uint64_t i = 0; i < 4; ++i) {
      jpegs.push_back(make_jpeg(i));
      const std::int64_t stamp = 1'700'000'200'000'000'000 + static_cast<std::int64_t>(i) * 50'000'000;
      auto plan = sim::ros2::plan_compressed_image("jpeg", jpegs.back().size(),
                                                   {sim::ros2::Time::from_ns(stamp), "front"});
      ASSERT_TRUE(plan);
      std::vector<std::byte> message(plan->size());
      ASSERT_EQ(plan->write(jpegs.back(), message), message.size());
      ASSERT_FALSE(writer->write({channel, static_cast<std::uint32_t>(i), static_cast<std::uint64_t>(stamp),
                                  static_cast<std::uint64_t>(stamp)}, message));
    }
    ASSERT_FALSE(writer->close());
  }
  const std::string out = unique_stream("jpeg");
  cleanup.names = {out};
  FrameCollector frames(out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/front_jpeg=" + out,
                                         "--wait-for-readers"});
  EXPECT_EQ(played.code, 0) << played.err;
  frames.wait_for(4);
  frames.stop();
  const auto got = frames.frames();
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.size() + frames.skipped(), 4u);
  for (const auto& f : got) {
    ASSERT_LE(f.seq, 4u);
    EXPECT_TRUE(f.bytes == jpegs[f.seq - 1]) << "jpeg " << f.seq << " differs";
    EXPECT_EQ(f.layout.kind, sim::LayoutKind::image);
    EXPECT_EQ(f.layout.image.format, sim::PixelFormat::mjpeg);
    EXPECT_EQ(f.layout.image.width, 64u);
    EXPECT_EQ(f.layout.image.height, 48u);
    EXPECT_EQ(f.stamp_ns, 1'700'000'200'000'000'000 + static_cast<std::int64_t>(f.seq - 1) * 50'000'000);
  }
}

}  // namespace

namespace {

// Small files of one Image topic for the review's cases (docs/mcap.md, "Damaged files").
constexpr std::uint32_t kTinyWidth = 4, kTinyHeight = 2;

std::vector<std::byte> tiny_image_message(std::uint32_t index, std::int64_t stamp_ns) {
  const auto layout = sim::ImageLayout::packed(kTinyWidth, kTinyHeight, sim::PixelFormat::rgb8);
  std::vector<std::byte> pixels(layout.frame_bytes(), static_cast<std::byte>(index + 1));
  auto plan = sim::ros2::plan_image(layout, pixels.size(), {sim::ros2::Time::from_ns(stamp_ns), "cam"});
  std::vector<std::byte> message(plan ? plan->size() : 0);
  if (plan) plan->write(pixels, message);
  return message;
}

std::string image_schema() {
  return std::string(sim::ros2::ros2msg_schema(sim::ros2::MessageType::image));
}

constexpr std::uint64_t kTinyStart = 1'700'000'300'000'000'000;

TEST(SimPlay, PlaysAFileWhoseSummaryDoesNotRepeatTheChannels) {
  sim::testing::TempFile file;
  {
    sim::mcap::WriterOptions options;
    options.repeat_channels = false;  // like Go's SkipRepeatedChannelInfos
    auto writer = sim::mcap::Writer::create(file.path(), options);
    ASSERT_TRUE(writer);
    const auto schema = writer->add_schema("sensor_msgs/msg/Image", "ros2msg", image_schema());
    const auto channel = writer->add_channel(schema, "/tiny", "cdr", {});
    for (std::uint32_t i = 0; i < 5; ++i) {
      const std::uint64_t t = kTinyStart + i * 10'000'000ull;
      ASSERT_FALSE(writer->write({channel, i, t, t}, tiny_image_message(i, static_cast<std::int64_t>(t))));
    }
    ASSERT_FALSE(writer->close());
  }
  sim::testing::StreamCleanup cleanup;
  const std::string out = unique_stream("nosum");
  cleanup.names = {out};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/tiny=" + out, "--max-rate"});
  EXPECT_EQ(played.code, 0) << played.err;
  EXPECT_NE(played.err.find(out + " 5"), std::string::npos) << played.err;  // the summary line
}

TEST(SimPlay, PlaysEveryMessageOfAFileWhoseMessagesAreOutOfOrder) {
  sim::testing::TempFile file;
  sim::testing::RawMcap raw;
  raw.schema(1, "sensor_msgs/msg/Image", image_schema()).channel(1, 1, "/tiny");
  for (const std::uint64_t second : {2, 1, 3}) {  // no Statistics tell where the file starts
    const std::uint64_t t = kTinyStart + second * 1'000'000'000ull;
    raw.message(1, static_cast<std::uint32_t>(second), t, tiny_image_message(0, static_cast<std::int64_t>(t)));
  }
  sim::testing::write_bytes(file.path(), raw.finish());
  sim::testing::StreamCleanup cleanup;
  const std::string out = unique_stream("order");
  cleanup.names = {out};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/tiny=" + out, "--max-rate"});
  EXPECT_EQ(played.code, 0) << played.err;
  EXPECT_NE(played.err.find(out + " 3"), std::string::npos) << played.err;
}

TEST(SimPlay, ADamagedRecordIsSaidAndTheFramesAroundItPlayWithExitCode1) {
  sim::testing::TempFile file;
  {
    auto writer = sim::mcap::Writer::create(file.path());
    ASSERT_TRUE(writer);
    const auto schema = writer->add_schema("sensor_msgs/msg/Image", "ros2msg", image_schema());
    const auto channel = writer->add_channel(schema, "/tiny", "cdr", {});
    for (std::uint32_t i = 0; i < 6; ++i) {
      const std::uint64_t t = kTinyStart + i * 10'000'000ull;
      ASSERT_FALSE(writer->write({channel, i, t, t}, tiny_image_message(i, static_cast<std::int64_t>(t))));
    }
    ASSERT_FALSE(writer->close());
  }
  auto bytes = sim::testing::read_bytes(file.path());
  std::uint64_t header_length;
  std::memcpy(&header_length, bytes.data() + 9, 8);
  ASSERT_EQ(bytes[8 + 9 + header_length], std::byte{0x03});
  bytes[8 + 9 + header_length] = std::byte{0x02};  // the Schema record now reads as a Footer
  sim::testing::write_bytes(file.path(), bytes);
  sim::testing::StreamCleanup cleanup;
  const std::string out = unique_stream("footer");
  cleanup.names = {out};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/tiny=" + out, "--max-rate"});
  EXPECT_EQ(played.code, 1) << played.err;
  EXPECT_NE(played.err.find("Footer record"), std::string::npos) << played.err;
  EXPECT_NE(played.err.find(out + " 6"), std::string::npos) << played.err;
}

TEST(SimPlay, ATinyFileCannotReserveGigabytesOfSharedMemory) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const std::string out = unique_stream("huge");
  cleanup.names = {out};
  sim::testing::RawMcap raw;
  raw.schema(1, "sensor_msgs/msg/Image", image_schema())
      .channel(1, 1, out, {{"sim.kind", "bytes"}, {"sim.capacity", std::to_string(1ull << 30)}});
  sim::testing::write_bytes(file.path(), raw.finish());
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--max-rate"});
  EXPECT_EQ(played.code, 1) << played.err;
  EXPECT_NE(played.err.find("--max-capacity"), std::string::npos) << played.err;
  EXPECT_FALSE(sim::inspect(out)) << "a 1 GiB stream was created";
}

TEST(SimPlayAndRecord, RefuseAFifoInsteadOfWaitingForIt) {
  sim::testing::TempFile fifo(".fifo");
  ASSERT_EQ(::mkfifo(fifo.path().c_str(), 0600), 0);
  Process player({SIM_PLAY, fifo.path()});
  EXPECT_EQ(player.wait(std::chrono::seconds(20)), 1) << player.err();
  EXPECT_NE(player.err().find("not a regular file"), std::string::npos) << player.err();

  sim::testing::StreamCleanup cleanup;
  const std::string camera_stream = unique_stream("fifo_cam");
  cleanup.names = {camera_stream};
  Process camera({MCAP_TEST_CAMERA, "--stream", camera_stream, "--width", "8", "--height", "8",
                  "--frames", "0", "--fps", "30"});
  ASSERT_TRUE(camera.wait_for_line("ready"));
  Process recorder({SIM_RECORD, "-o", fifo.path(), "--duration", "1", camera_stream});
  EXPECT_EQ(recorder.wait(std::chrono::seconds(20)), 1) << recorder.err();
  EXPECT_NE(recorder.err().find("FIFO"), std::string::npos) << recorder.err();
  camera.signal(SIGTERM);
}

TEST(SimPlay, PrintsTheTopicsOfAFileWithoutTheirControlCharacters) {
  sim::testing::TempFile file;
  sim::testing::RawMcap raw;
  raw.schema(1, "sensor_msgs/msg/Image", image_schema()).channel(1, 1, "/cam\x1b]0;owned\x07");
  sim::testing::write_bytes(file.path(), raw.finish());
  const auto played = sim::testing::run({SIM_PLAY, file.path()});
  EXPECT_EQ(played.code, 1);
  EXPECT_EQ(played.err.find('\x1b'), std::string::npos) << played.err;
  EXPECT_EQ(played.err.find('\x07'), std::string::npos) << played.err;
  EXPECT_NE(played.err.find("/cam\\x1b]0;owned\\x07"), std::string::npos) << played.err;
}

// MCAP review L4: a small file naming many channels made one region each (500 from a 45 KB
// file), and they stayed after sim_play ended. A crafted file of byte streams, shapes from
// their metadata, so each channel makes its region before any message.
std::vector<std::string> byte_channels(sim::testing::RawMcap& raw, sim::testing::StreamCleanup& cleanup,
                                       int count, std::uint64_t capacity, const std::string& what) {
  raw.schema(1, "sensor_msgs/msg/Image", image_schema());
  std::vector<std::string> streams;
  for (int i = 0; i < count; ++i) {
    streams.push_back(unique_stream(what + std::to_string(i)));
    raw.channel(static_cast<std::uint16_t>(i + 1), 1, streams.back(),
                {{"sim.kind", "bytes"}, {"sim.capacity", std::to_string(capacity)}});
  }
  cleanup.names.insert(cleanup.names.end(), streams.begin(), streams.end());
  return streams;
}

bool removed(const std::string& stream) {
  const auto status = sim::inspect(stream);
  return !status && status.error().code == sim::ErrorCode::not_found;
}

std::size_t existing(const std::vector<std::string>& streams) {
  return static_cast<std::size_t>(
      std::count_if(streams.begin(), streams.end(), [](const std::string& s) { return bool(sim::inspect(s)); }));
}

TEST(SimPlay, ARecordingOfMoreStreamsThanMaxStreamsIsRefusedBeforeAnyIsCreated) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  sim::testing::RawMcap raw;
  const auto streams = byte_channels(raw, cleanup, 65, 64, "many");
  sim::testing::write_bytes(file.path(), raw.finish());
  const auto refused = sim::testing::run({SIM_PLAY, file.path(), "--max-rate"});
  EXPECT_EQ(refused.code, 1) << refused.err;
  EXPECT_NE(refused.err.find("would make 65 streams, more than --max-streams 64"), std::string::npos)
      << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_EQ(existing(streams), 0u);
  const auto allowed = sim::testing::run({SIM_PLAY, file.path(), "--max-rate", "--max-streams", "65",
                                          "--keep-streams"});
  EXPECT_EQ(allowed.code, 0) << allowed.err;
  EXPECT_EQ(existing(streams), 65u);
}

TEST(SimPlay, TheStreamsOfOneRecordingShareOneSharedMemoryBudget) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  sim::testing::RawMcap raw;
  // 512 KiB a slot: within what a channel may ask for without a message (1 MiB).
  const auto streams = byte_channels(raw, cleanup, 3, 512u << 10, "budget");
  sim::testing::write_bytes(file.path(), raw.finish());
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--max-rate", "--max-shm", "2",
                                         "--keep-streams"});
  EXPECT_EQ(played.code, 1) << played.err;
  EXPECT_NE(played.err.find("stream " + streams[1] + " would take 1.0 MiB of shared memory"), std::string::npos)
      << played.err;
  EXPECT_NE(played.err.find("--max-shm 2 MiB"), std::string::npos) << played.err;
  EXPECT_TRUE(sim::inspect(streams[0]));  // the first fits, the others are not created
  EXPECT_FALSE(sim::inspect(streams[1]));
  EXPECT_FALSE(sim::inspect(streams[2]));
}

// No file reaches this check any more (a stream may take only a few times what its file holds),
// so the budget is asked directly for more than /dev/shm has free.
TEST(SimPlay, AStreamLargerThanWhatDevShmHasFreeIsRefusedBeforeItIsReserved) {
  struct statvfs shm {};
  ASSERT_EQ(::statvfs("/dev/shm", &shm), 0);
  const std::uint64_t free_bytes = static_cast<std::uint64_t>(shm.f_bavail) * shm.f_frsize;
  sim::play::ShmBudget budget(UINT64_MAX);
  const auto refused = budget.take("/nofree", 0, free_bytes + (std::uint64_t{1} << 30));
  ASSERT_TRUE(refused);
  EXPECT_NE(refused->message.find("MiB are free"), std::string::npos) << refused->message;
  EXPECT_FALSE(budget.take("/fits", 0, 4096)) << "the refused bytes were counted as taken";
}

// MCAP review L4: a 6 KB file of 64 channels, each asking 255 MiB a slot in its metadata, made
// 2 GiB of regions (the --max-shm default) before it played a frame. What a channel holds
// bounds what it may ask for: here each holds 4x2 pictures, so its stream is sized from them,
// and a channel holding nothing makes no stream. --max-shm 64 keeps a failing run from
// reserving the 2 GiB it asks for.
TEST(SimPlay, ASmallFileAskingForGigabytesGetsStreamsSizedFromTheMessagesItHolds) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  sim::testing::RawMcap raw;
  const std::uint64_t asked = std::uint64_t{128} << 20;  // 256 MiB a region, 2 GiB for eight
  const std::string layout_keys_of_16384x8192_mono8[][2] = {
      {"sim.kind", "image"}, {"sim.image.width", "16384"}, {"sim.image.height", "8192"},
      {"sim.image.channels", "1"}, {"sim.image.stride", "16384"},
      {"sim.image.format", std::to_string(static_cast<std::uint32_t>(sim::PixelFormat::mono8))},
      {"sim.image.bit_depth", "8"}};
  std::vector<std::pair<std::string, std::string>> metadata{{"sim.capacity", std::to_string(asked)}};
  for (const auto& kv : layout_keys_of_16384x8192_mono8) metadata.emplace_back(kv[0], kv[1]);
  raw.schema(1, "sensor_msgs/msg/Image", image_schema());
  std::vector<std::string> streams;
  for (std::uint16_t i = 1; i <= 9; ++i) {
    streams.push_back(unique_stream("asks" + std::to_string(i)));
    raw.channel(i, 1, streams.back(), metadata);
  }
  cleanup.names = streams;
  for (std::uint32_t n = 0; n < 3; ++n) {
    const std::uint64_t t = kTinyStart + n * 10'000'000ull;
    for (std::uint16_t i = 1; i <= 8; ++i) raw.message(i, n, t, tiny_image_message(n, static_cast<std::int64_t>(t)));
  }
  const auto bytes = raw.finish();
  ASSERT_LT(bytes.size(), 8000u);
  sim::testing::write_bytes(file.path(), bytes);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--max-rate", "--max-shm", "64", "--keep-streams"});
  EXPECT_EQ(played.code, 0) << played.err;
  for (int i = 0; i < 8; ++i) {
    auto status = sim::inspect(streams[static_cast<std::size_t>(i)]);
    ASSERT_TRUE(status) << streams[static_cast<std::size_t>(i)] << " was not made: " << played.err;
    EXPECT_EQ(status->frames_published, 3u);
    EXPECT_LE(status->capacity, sim::play::kRoomFloor);
    EXPECT_EQ(status->layout.image.width, kTinyWidth);
  }
  EXPECT_NE(played.err.find("topic " + streams[0] + " asks for 128.0 MiB per frame but its first message holds "),
            std::string::npos) << played.err;
  EXPECT_NE(played.err.find("so its stream is sized from its messages instead; check where the file came from "
                            "(sim_record never writes this) (and so do 8 more topics)"),
            std::string::npos) << played.err;
  EXPECT_EQ(played.err.find("asks for", played.err.find("asks for") + 1), std::string::npos)
      << "one sentence for the nine topics: " << played.err;
  EXPECT_FALSE(sim::inspect(streams[8])) << "a channel holding nothing made a stream";
}

std::string tiny_image_file(const std::string& path, std::uint64_t interval_ns) {
  const std::string topic = unique_stream("ends");
  sim::testing::RawMcap raw;
  raw.schema(1, "sensor_msgs/msg/Image", image_schema()).channel(1, 1, topic);
  for (std::uint32_t i = 0; i < 5; ++i) {
    const std::uint64_t t = kTinyStart + i * interval_ns;
    raw.message(1, i, t, tiny_image_message(i, static_cast<std::int64_t>(t)));
  }
  sim::testing::write_bytes(path, raw.finish());
  return topic;
}

TEST(SimPlay, RemovesTheStreamsItMadeWhenItEndsOrIsStoppedUnlessToldToKeepThem) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const std::string stream = tiny_image_file(file.path(), 10'000'000);
  cleanup.names = {stream};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--max-rate"});
  EXPECT_EQ(played.code, 0) << played.err;
  EXPECT_NE(played.err.find(stream + " 5"), std::string::npos) << played.err;  // it did play
  EXPECT_TRUE(removed(stream));

  const auto kept = sim::testing::run({SIM_PLAY, file.path(), "--max-rate", "--keep-streams"});
  EXPECT_EQ(kept.code, 0) << kept.err;
  auto status = sim::inspect(stream);
  ASSERT_TRUE(status) << status.error().message;
  EXPECT_EQ(status->frames_published, 5u);
  ASSERT_TRUE(sim::destroy(stream));

  // Stopped (Ctrl-C, SIGTERM) in the middle of a slow recording: removed all the same.
  const std::string slow = tiny_image_file(file.path(), 60'000'000'000);
  cleanup.names.push_back(slow);
  Process player({SIM_PLAY, file.path(), "--quiet"});
  ASSERT_TRUE(player.wait_for_line("playing")) << player.err();
  for (int i = 0; i < 3000; ++i) {  // until the first frame is out (bounded: 30 s)
    auto now = sim::inspect(slow);
    if (now && now->frames_published > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(sim::inspect(slow)) << "the stream was never created";
  player.signal(SIGTERM);
  EXPECT_EQ(player.wait(), 0) << player.err();
  EXPECT_TRUE(removed(slow));
}

TEST(SimRecord, ExitsWith1WhenTheLastChunkCannotBeWritten) {
  sim::testing::StreamCleanup cleanup;
  const std::string camera_stream = unique_stream("full_cam");
  cleanup.names = {camera_stream};
  Process camera({MCAP_TEST_CAMERA, "--stream", camera_stream, "--width", "64", "--height", "48",
                  "--frames", "0", "--fps", "30"});
  ASSERT_TRUE(camera.wait_for_line("ready"));
  // Every frame fits in the one chunk written at the end, when /dev/full refuses it.
  Process recorder({SIM_RECORD, "-o", "/dev/full", "--duration", "1", "--json", camera_stream});
  EXPECT_EQ(recorder.wait(), 1) << recorder.err();
  EXPECT_NE(recorder.err().find("No space left"), std::string::npos) << recorder.err();
  EXPECT_EQ(json_number(recorder.out(), camera_stream, "frames"), 0u) << recorder.out();  // none reached it
  camera.signal(SIGTERM);
}

// Review turn 4 M6: a description sim_record cannot read for a moment (its writer stopped in the
// middle of an update, as under SIGSTOP, a debugger or a loaded host) is read again at a later
// frame: once the writer goes on, the images carry the sensor's frame and their CameraInfo.
TEST(SimRecord, ADescriptionUnreadableForAMomentIsReadAgainAtALaterFrame) {
  sim::testing::StreamCleanup cleanup;
  sim::testing::TempFile file;
  const std::string name = unique_stream("stuck_cam");
  cleanup.names = {name};
  sim::StreamSpec spec;
  spec.name = name;
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(4, 3, sim::PixelFormat::mono8));
  sim::SensorInfo sensor;
  sensor.frame_id = "stuck_cam_optical";
  sim::CameraCalibration c;
  c.width = 4;
  c.height = 3;
  c.distortion_model = "plumb_bob";
  c.d = {0, 0, 0, 0, 0};
  c.k = {10, 0, 2, 0, 10, 1.5, 0, 0, 1};
  c.p = {10, 0, 2, 0, 0, 10, 1.5, 0, 0, 0, 1, 0};
  sensor.calibration = c;
  spec.sensor = sensor;
  auto writer = sim::Writer::create(spec);
  ASSERT_TRUE(writer) << writer.error().message;

  // The description's word as a writer leaves it in the middle of an update.
  const int fd = open(("/dev/shm/sim." + name.substr(1)).c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  const auto at = static_cast<off_t>(sim::detail::kHeaderOffset + offsetof(sim::detail::RegionHeader, sensor));
  std::uint64_t word = 0;
  ASSERT_EQ(pread(fd, &word, sizeof word, at), static_cast<ssize_t>(sizeof word));
  const std::uint64_t writing = word | sim::detail::kSensorWriting;
  ASSERT_EQ(pwrite(fd, &writing, sizeof writing, at), static_cast<ssize_t>(sizeof writing));

  Process recorder({SIM_RECORD, "-o", file.path(), name, "--json"});
  ASSERT_TRUE(recorder.wait_for_line("recording")) << recorder.err();
  const std::byte pixels[12] = {};
  std::int64_t stamp_ns = 1'700'000'000'000'000'000;
  auto publish = [&](int frames) {
    for (int n = 0; n < frames; ++n) {
      stamp_ns += 20'000'000;
      ASSERT_TRUE((*writer).write(pixels, sizeof pixels, stamp_ns) == sim::WriteStatus::ok);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  publish(100);  // read by the recorder while the description cannot be read
  ASSERT_EQ(pwrite(fd, &word, sizeof word, at), static_cast<ssize_t>(sizeof word));  // the writer goes on
  close(fd);
  publish(50);
  recorder.signal(SIGINT);
  EXPECT_EQ(recorder.wait(), 0) << recorder.err();
  EXPECT_NE(recorder.err().find("stopped in the middle"), std::string::npos)
      << "the recorder never met the unreadable description: " << recorder.err();

  auto reader = sim::mcap::Reader::open(file.path());
  ASSERT_TRUE(reader) << reader.error().message;
  std::string last_frame_id;
  int camera_infos = 0;
  while (auto m = reader->next()) {
    const auto* schema = reader->schema_of(reader->channels().at(m->header.channel_id));
    if (schema && schema->name == "sensor_msgs/msg/CameraInfo") ++camera_infos;
    if (schema && schema->name == "sensor_msgs/msg/Image") {
      if (auto image = sim::ros2::decode_image(m->data)) last_frame_id = std::string(image->header.frame_id);
    }
  }
  EXPECT_EQ(last_frame_id, "stuck_cam_optical") << recorder.err();
  EXPECT_GT(camera_infos, 0) << recorder.err();
}

}  // namespace
