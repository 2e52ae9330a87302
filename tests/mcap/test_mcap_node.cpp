// SPDX-License-Identifier: Apache-2.0
// Files sim_record writes, read by Foxglove's own MCAP library (@mcap/core, npm) in a Node script
// (node/read_mcap.mjs): header and profile, the summary's statistics, every channel with its
// schema and encoding, the message counts per channel from the indexes and from a front-to-back
// read with every CRC checked, and the data section CRC.
#include <gtest/gtest.h>

#include <sstream>

#include "mcap_test_files.hpp"
#include "record_play_support.hpp"

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
