// SPDX-License-Identifier: Apache-2.0
// MCAP between SIM and Foxglove's own library (@mcap/core, npm), in Node scripts:
// - files sim_record writes, read by node/read_mcap.mjs: header and profile, the summary's
//   statistics, every channel with its schema and encoding, the message counts per channel from
//   the indexes and from a front-to-back read with every CRC checked, and the data section CRC;
// - a ROS 2 file node/write_ros2_mcap.mjs writes (no SIM metadata), played by sim_play.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

#include "mcap_test_files.hpp"
#include "record_play_support.hpp"
#include "sim/lidar_point.hpp"

namespace {

std::string line_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) return line;
  }
  return {};
}

class ReadByMcapCore : public ::testing::TestWithParam<std::string> {};

TEST_P(ReadByMcapCore, SeesEveryChannelSchemaMessageAndTheSummary) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto rec = sim::testing::record(file.path(), GetParam(), cleanup);
  auto ours = sim::testing::read_recording(file.path());
  const std::size_t camera = ours[rec.camera].size();
  const std::size_t lidar = ours[rec.lidar].size();
  ASSERT_GT(camera, 0u);
  ASSERT_GT(lidar, 0u);

  const auto node = sim::testing::run({NODE, READ_MCAP_SCRIPT, file.path()});
  ASSERT_EQ(node.code, 0) << node.err;
  EXPECT_EQ(line_starting(node.out, "header "), "header ros2 sim_record") << node.out;
  const std::string summary = line_starting(node.out, "summary ");
  EXPECT_NE(summary.find("messages=" + std::to_string(camera + lidar) + " "), std::string::npos) << summary;
  EXPECT_NE(summary.find("schemas=2 channels=2 data_crc=ok"), std::string::npos) << summary;

  auto expect_channel = [&](const std::string& topic, const std::string& schema, std::size_t count,
                            const std::string& kind) {
    const std::string line = line_starting(node.out, "channel " + topic + " ");
    const std::string n = std::to_string(count);
    EXPECT_NE(line.find(" cdr " + schema + " ros2msg "), std::string::npos) << line;
    EXPECT_NE(line.find(" stats=" + n + " indexed=" + n + " streamed=" + n + " ordered=yes qos=yes"),
              std::string::npos)
        << line;
    EXPECT_NE(line.find(" meta:sim.kind=" + kind), std::string::npos) << line;
  };
  expect_channel(rec.camera, "sensor_msgs/msg/Image", camera, "image");
  expect_channel(rec.lidar, "sensor_msgs/msg/PointCloud2", lidar, "points");
}

INSTANTIATE_TEST_SUITE_P(Mcap, ReadByMcapCore, ::testing::Values("zstd", "lz4", "none"));

TEST(ReadByMcapCore, RejectsADamagedChunk) {
  // The reference reader must disagree with a file we damaged, or the test above proves little.
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto rec = sim::testing::record(file.path(), "none", cleanup);
  auto bytes = sim::testing::read_bytes(file.path());
  bytes[bytes.size() / 3] ^= std::byte{0x40};  // inside the data section, in some chunk
  sim::testing::write_bytes(file.path(), bytes);
  const auto node = sim::testing::run({NODE, READ_MCAP_SCRIPT, file.path()});
  EXPECT_EQ(node.code, 1) << node.out;
  EXPECT_NE(node.err.find("CRC"), std::string::npos) << node.err;
}

}  // namespace

namespace {

// A ROS 2 recording made outside SIM (node/write_ros2_mcap.mjs: @mcap/core's writer and
// Foxglove's CDR serializer) plays into SIM streams with every value where it belongs.
TEST(PlayForeignRecording, PutsEveryPointAndPixelOfAnotherWritersFileIntoSim) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto written = sim::testing::run({NODE, WRITE_ROS2_SCRIPT, file.path()});
  ASSERT_EQ(written.code, 0) << written.err;
  const std::string cloud_out = sim::testing::unique_stream("ext_cloud");
  const std::string image_out = sim::testing::unique_stream("ext_image");
  cleanup.names = {cloud_out, image_out};
  sim::testing::FrameCollector clouds(cloud_out);
  sim::testing::FrameCollector images(image_out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/ext/cloud=" + cloud_out,
                                         "--remap", "/ext/image=" + image_out, "--wait-for-readers",
                                         "--rate", "20"});
  EXPECT_EQ(played.code, 0) << played.err;
  clouds.wait_for(5);
  images.wait_for(5);
  clouds.stop();
  images.stop();

  const auto cloud_frames = clouds.frames();
  ASSERT_FALSE(cloud_frames.empty());
  EXPECT_EQ(cloud_frames.size() + clouds.skipped(), 5u);
  for (const auto& f : cloud_frames) {
    const std::uint64_t m = f.seq - 1;
    EXPECT_EQ(f.stamp_ns, (1700000100 + static_cast<std::int64_t>(m)) * 1'000'000'000 + 5000);
    ASSERT_EQ(f.layout.kind, sim::LayoutKind::points);
    EXPECT_EQ(f.layout.points.type, sim::PointType::lidar_point);  // it has rings
    ASSERT_EQ(f.bytes.size(), 100 * sizeof(sim::LidarPoint));
    std::vector<sim::LidarPoint> points(100);
    std::memcpy(points.data(), f.bytes.data(), f.bytes.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      EXPECT_EQ(points[k].x, static_cast<float>(m) + static_cast<float>(k) / 2);
      EXPECT_EQ(points[k].y, -static_cast<float>(k));
      EXPECT_EQ(points[k].z, static_cast<float>(k) / 4);
      EXPECT_EQ(points[k].intensity, static_cast<float>(k));
      EXPECT_EQ(points[k].ring, k % 64);
    }
  }
  const auto image_frames = images.frames();
  ASSERT_FALSE(image_frames.empty());
  EXPECT_EQ(image_frames.size() + images.skipped(), 5u);
  for (const auto& f : image_frames) {
    const std::uint64_t m = f.seq - 1;
    auto layout = sim::ImageLayout::packed(4, 3, sim::PixelFormat::rgb8);
    layout.stride = 16;  // the row padding is kept
    EXPECT_EQ(f.layout, sim::Layout::of(layout)) << f.layout.describe();
    ASSERT_EQ(f.bytes.size(), 48u);
    for (std::size_t j = 0; j < f.bytes.size(); ++j) {
      EXPECT_EQ(static_cast<std::uint8_t>(f.bytes[j]), (3 * m + j) % 256);
    }
  }
}

}  // namespace
