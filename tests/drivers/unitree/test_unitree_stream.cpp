// SPDX-License-Identifier: Apache-2.0
// LidarStream, the path every Unitree program takes from bytes to SIM: real shared memory read
// back with sim::Reader, compared with what the decoder alone makes of the same bytes.
#include <gtest/gtest.h>

#include <cstring>
#include <optional>
#include <span>
#include <vector>

#include "allocation_counter.hpp"
#include "sim/reader.hpp"
#include "sim/unitree/lidar_stream.hpp"
#include "sim_test/streams.hpp"
#include "unitree_encoder.hpp"
#include "vector_sink.hpp"

namespace {

using namespace unitree_test;
using sim::testing::StreamGuard;
using sim::unitree::LidarStream;
using sim::unitree::LidarStreamConfig;

L2PointSpec packet_spec(std::uint32_t seq) {
  L2PointSpec s;
  s.seq = seq;
  s.stamp_sec = 1000;
  s.stamp_nsec = seq * 4'000'000;
  s.angle_min = -0.2F;
  s.angle_increment = 0.01F;
  s.com_horizontal_angle_start = 0.1F * static_cast<float>(seq);
  s.time_increment = 1.5e-5F;
  for (std::size_t j = 0; j < 300; ++j) {
    s.ranges[j] = static_cast<std::uint16_t>((j % 5 == 0) ? 0 : 900 + 7 * j + seq);
    s.intensities[j] = static_cast<std::uint8_t>(j + seq);
  }
  return s;
}

// `count` L2 point packets from `first_seq`, one IMU packet after each third.
Bytes l2_wire(std::uint32_t first_seq, std::uint32_t count) {
  Bytes wire;
  for (std::uint32_t i = 0; i < count; ++i) {
    wire = concat({wire, l2_point_packet(packet_spec(first_seq + i))});
    if (i % 3 == 2) wire = concat({wire, l2_imu_packet({})});
  }
  return wire;
}

LidarStreamConfig config_for(const std::string& name, std::uint32_t scan_packets) {
  LidarStreamConfig config;
  config.stream = name;
  config.imu_stream = sim::unitree::default_imu_stream(name);
  config.decoder.packets_per_scan = scan_packets;
  return config;
}

// What the decoder alone makes of `bytes` (host time `host_ns`).
std::vector<Scan> decoded(const sim::unitree::DecoderOptions& options, const Bytes& bytes, std::int64_t host_ns) {
  VectorSink sink(sim::unitree::Decoder::max_points_per_scan(options));
  sim::unitree::Decoder decoder(options, sink);
  decoder.push(bytes, host_ns);
  return sink.scans;
}

struct Frame {
  std::vector<sim::LidarPoint> points;
  sim::FrameInfo info;
};

std::optional<Frame> newest_frame(const std::string& name) {
  auto reader = sim::Reader::open(name);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return std::nullopt;
  }
  std::vector<std::byte> buffer(reader->capacity());
  Frame frame;
  if (reader->read_next(buffer, frame.info, std::chrono::seconds(20)) != sim::ReadStatus::new_frame) return std::nullopt;
  frame.points.resize(frame.info.size / sizeof(sim::LidarPoint));
  std::memcpy(frame.points.data(), buffer.data(), frame.info.size);
  return frame;
}

void expect_same_points(const std::vector<sim::LidarPoint>& got, const std::vector<sim::LidarPoint>& want) {
  ASSERT_EQ(got.size(), want.size());
  EXPECT_EQ(0, std::memcmp(got.data(), want.data(), got.size() * sizeof(sim::LidarPoint)));
}

TEST(UnitreeLidarStream, PublishesEveryScanOfAChunkAsTheDecoderMakesIt) {
  StreamGuard guard;
  const std::string name = sim::testing::unique_name("unitree_stream");
  guard.names = {name, name + ".imu"};
  const LidarStreamConfig config = config_for(name, 3);
  auto stream = LidarStream::create(config);
  ASSERT_TRUE(stream) << stream.error().message;
  const Bytes wire = l2_wire(0, 7);  // two scans of three packets and one more packet
  EXPECT_EQ(stream->push(std::span<const std::uint8_t>(wire), 5'000), 2U) << "one chunk completes two scans";
  EXPECT_EQ(stream->published().frames, 2U);
  EXPECT_EQ(stream->published().imu_samples, 2U);
  EXPECT_EQ(stream->counters().framing.packets, 9U);

  const auto expected = decoded(config.decoder, wire, 5'000);
  ASSERT_EQ(expected.size(), 2U);
  const auto frame = newest_frame(name);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->info.seq, 2U);
  expect_same_points(frame->points, expected[1].points);
  EXPECT_EQ(frame->info.stamp_ns, 5'000) << "host time: the arrival of the scan's bytes";
  EXPECT_EQ(frame->info.receive_ns, 5'000);
  auto imu = sim::inspect(name + ".imu");
  ASSERT_TRUE(imu.has_value());
  EXPECT_EQ(imu->frames_published, 2U);
}

TEST(UnitreeLidarStream, TheSummaryKeepsTheKeysScriptsParse) {
  StreamGuard guard;
  const std::string name = sim::testing::unique_name("unitree_summary");
  guard.names = {name, name + ".imu"};
  auto stream = LidarStream::create(config_for(name, 3));
  ASSERT_TRUE(stream) << stream.error().message;
  Bytes wire = l2_wire(0, 3);
  wire = concat({wire, l2_point_packet(packet_spec(5))});  // two packets lost
  stream->push(std::span<const std::uint8_t>(wire), 1);
  const std::string summary = stream->describe_counters(true);
  EXPECT_EQ(summary.rfind("frames=1 packets=5 lost=2 malformed=0 imu=1 failed=0 ", 0), 0U) << summary;
  const std::string status = stream->describe_counters();
  EXPECT_EQ(status.rfind("frames 1 packets 5 lost 2 malformed 0 imu 1 points/frame ", 0), 0U) << status;
}

TEST(UnitreeLidarStream, ResetForgetsTheScanInProgress) {
  StreamGuard guard;
  const std::string name = sim::testing::unique_name("unitree_reset");
  guard.names = {name, name + ".imu"};
  const LidarStreamConfig config = config_for(name, 3);
  auto stream = LidarStream::create(config);
  ASSERT_TRUE(stream) << stream.error().message;
  stream->push(std::span<const std::uint8_t>(l2_wire(0, 2)), 1);
  stream->reset();
  const Bytes after = l2_wire(10, 3);
  EXPECT_EQ(stream->push(std::span<const std::uint8_t>(after), 2), 1U);
  const auto expected = decoded(config.decoder, after, 2);
  ASSERT_EQ(expected.size(), 1U);
  const auto frame = newest_frame(name);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->info.seq, 1U);
  expect_same_points(frame->points, expected[0].points);
}

TEST(UnitreeLidarStream, TheStampOffsetMovesTheL2sOwnStampsNotHostStamps) {
  for (const auto source : {sim::unitree::TimeSource::sensor, sim::unitree::TimeSource::host}) {
    StreamGuard guard;
    const std::string name = sim::testing::unique_name("unitree_offset");
    guard.names = {name, name + ".imu"};
    LidarStreamConfig config = config_for(name, 3);
    config.decoder.time_source = source;
    auto stream = LidarStream::create(config);
    ASSERT_TRUE(stream) << stream.error().message;
    stream->set_stamp_offset(7'000'000'000);
    EXPECT_EQ(stream->stamp_offset(), 7'000'000'000);
    stream->push(std::span<const std::uint8_t>(l2_wire(0, 3)), 123);
    const auto frame = newest_frame(name);
    ASSERT_TRUE(frame);
    const std::int64_t sensor_stamp = 1000LL * 1'000'000'000;  // packet 0: 1000 s + 0 ns
    EXPECT_EQ(frame->info.stamp_ns, source == sim::unitree::TimeSource::sensor ? sensor_stamp + 7'000'000'000 : 123);
    EXPECT_EQ(frame->info.receive_ns, 123);
  }
}

TEST(UnitreeLidarStream, APublishGateStampsEachScanOrDropsIt) {
  StreamGuard guard;
  const std::string name = sim::testing::unique_name("unitree_gate");
  guard.names = {name, name + ".imu"};
  LidarStreamConfig config = config_for(name, 3);
  int asked = 0;
  config.publish_gate = [&asked]() -> std::optional<std::int64_t> {
    ++asked;
    if (asked == 2) return std::nullopt;  // the second scan: the replay is stopping
    return 42'000 + asked;
  };
  auto stream = LidarStream::create(config);
  ASSERT_TRUE(stream) << stream.error().message;
  EXPECT_EQ(stream->push(std::span<const std::uint8_t>(l2_wire(0, 9)), 1), 2U);
  EXPECT_EQ(asked, 3);
  EXPECT_EQ(stream->published().frames, 2U);
  const auto frame = newest_frame(name);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->info.seq, 2U);
  EXPECT_EQ(frame->info.stamp_ns, 42'003);
}

TEST(UnitreeLidarStream, ABadStreamNameIsOneSentenceAndNoStream) {
  LidarStreamConfig config = config_for("no_slash", 3);
  auto stream = LidarStream::create(config);
  ASSERT_FALSE(stream);
  EXPECT_FALSE(stream.error().message.empty());
  EXPECT_EQ(stream.error().message.find('\n'), std::string::npos) << stream.error().message;
}

TEST(UnitreeLidarStream, NoAllocationPerPacketOrScan) {
  StreamGuard guard;
  const std::string name = sim::testing::unique_name("unitree_alloc");
  guard.names = {name, name + ".imu"};
  auto stream = LidarStream::create(config_for(name, 3));
  ASSERT_TRUE(stream) << stream.error().message;
  const Bytes warm = l2_wire(0, 3);
  stream->push(std::span<const std::uint8_t>(warm), 1);  // the first commit and clock check have run once
  const Bytes wire = l2_wire(3, 12);
  const std::uint64_t before = allocations();
  for (std::size_t off = 0; off < wire.size(); off += 700) {
    stream->push(std::span<const std::uint8_t>(wire).subspan(off, std::min<std::size_t>(700, wire.size() - off)), 2);
  }
  EXPECT_EQ(allocations(), before);
  EXPECT_EQ(stream->published().frames, 5U);
  EXPECT_EQ(stream->published().imu_samples, 5U);
}

}  // namespace
