// SPDX-License-Identifier: Apache-2.0
// sim_dump as a real process on a stream sim_replay_pcap filled: the PCD it writes through PCL
// must hold exactly the frame's points (x y z intensity, in order), and the sidecar its metadata.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "lidar_test/pcap_payloads.hpp"  // read_text
#include "lidar_test/pcd.hpp"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"

namespace {

namespace fs = std::filesystem;
using sim::testing::run;

const fs::path data_dir = SIM_HESAI_TEST_DATA;
const std::string capture = (data_dir / "pandar64_dual.pcap").string();
const std::string calibration = (data_dir / "pandar64.calibration.csv").string();

using lidar_test::read_pcd;
using lidar_test::read_text;
using Pcd = lidar_test::PointCloudFile;

// The newest frame of the stream, read directly.
std::vector<sim::LidarPoint> newest_frame(const std::string& stream, sim::FrameInfo& info) {
  auto reader = sim::Reader::open(stream);
  EXPECT_TRUE(reader);
  std::vector<std::byte> buffer(reader->capacity());
  EXPECT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
  std::vector<sim::LidarPoint> points(info.size / sizeof(sim::LidarPoint));
  std::memcpy(points.data(), buffer.data(), info.size);
  return points;
}

class DumpTool : public ::testing::Test {
 protected:
  void SetUp() override {
    stream_ = "/test_hesai_dump_" + std::to_string(::getpid()) + "_" +
              ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("sim_dump_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    const auto replay = run({SIM_REPLAY_PCAP, capture, "--stream", stream_, "--calibration",
                             calibration, "--max-rate"});
    ASSERT_EQ(replay.code, 0) << replay.err;
  }
  void TearDown() override {
    (void)sim::destroy(stream_, true);
    fs::remove_all(dir_);
  }
  std::string stream_;
  fs::path dir_;
};

TEST_F(DumpTool, BinaryPcdHoldsTheFramesPointsAndTheSidecarItsMetadata) {
  sim::FrameInfo info;
  const auto points = newest_frame(stream_, info);
  ASSERT_FALSE(points.empty());
  const auto result = run({SIM_DUMP, stream_, "--current", "--count", "1", "--out", dir_.string()});
  ASSERT_EQ(result.code, 0) << result.err;

  const std::string stem = stream_.substr(1) + "_" + std::string(8 - std::to_string(info.seq).size(), '0') +
                           std::to_string(info.seq);
  const Pcd pcd = read_pcd(dir_ / (stem + ".pcd"));
  EXPECT_EQ(pcd.fields, "x y z intensity");
  EXPECT_EQ(pcd.data, "binary");
  ASSERT_EQ(pcd.points, points.size());
  ASSERT_EQ(pcd.values.size(), points.size() * 4);
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(pcd.values[4 * i + 0], points[i].x) << i;
    ASSERT_EQ(pcd.values[4 * i + 1], points[i].y) << i;
    ASSERT_EQ(pcd.values[4 * i + 2], points[i].z) << i;
    ASSERT_EQ(pcd.values[4 * i + 3], points[i].intensity) << i;
  }
  const std::string json = read_text(dir_ / (stem + ".json"));
  EXPECT_NE(json.find("\"seq\": " + std::to_string(info.seq) + ","), std::string::npos) << json;
  EXPECT_NE(json.find("\"stamp_ns\": " + std::to_string(info.stamp_ns) + ","), std::string::npos);
  EXPECT_NE(json.find("\"publish_ns\": " + std::to_string(info.publish_ns) + ","), std::string::npos);
  EXPECT_NE(json.find("\"size\": " + std::to_string(info.size) + ","), std::string::npos);
  EXPECT_NE(json.find("\"point_type\": \"lidar_point\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"points\": " + std::to_string(points.size())), std::string::npos);
  EXPECT_NE(json.find("\"file\": \"" + stem + ".pcd\""), std::string::npos);
}

TEST_F(DumpTool, AsciiXyz) {
  sim::FrameInfo info;
  const auto points = newest_frame(stream_, info);
  const auto result = run({SIM_DUMP, stream_, "--current", "--out", dir_.string(), "--ascii", "--xyz"});
  ASSERT_EQ(result.code, 0) << result.err;
  std::vector<fs::path> pcds;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (entry.path().extension() == ".pcd") pcds.push_back(entry.path());
  }
  ASSERT_EQ(pcds.size(), 1u);
  const Pcd pcd = read_pcd(pcds[0]);
  EXPECT_EQ(pcd.fields, "x y z");
  EXPECT_EQ(pcd.data, "ascii");
  ASSERT_EQ(pcd.points, points.size());
  for (std::size_t i = 0; i < points.size(); i += 97) {  // ASCII keeps 8 significant digits
    EXPECT_NEAR(pcd.values[3 * i + 0], points[i].x, 1e-5) << i;
    EXPECT_NEAR(pcd.values[3 * i + 2], points[i].z, 1e-5) << i;
  }
}

TEST_F(DumpTool, ClearErrors) {
  // The replay ended: no new frame comes, so waiting for one times out with exit 1.
  const auto idle = run({SIM_DUMP, stream_, "--count", "1", "--timeout", "0.3", "--out", dir_.string()});
  EXPECT_EQ(idle.code, 1);
  EXPECT_NE(idle.err.find("no new frame"), std::string::npos) << idle.err;
  const auto missing = run({SIM_DUMP, stream_ + "_missing", "--out", dir_.string()});
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("no stream"), std::string::npos) << missing.err;
  EXPECT_EQ(run({SIM_DUMP, "--help"}).code, 0);
  EXPECT_EQ(run({SIM_DUMP}).code, 2);
  EXPECT_EQ(run({SIM_DUMP, stream_, "--count", "x"}).code, 2);
}

}  // namespace
