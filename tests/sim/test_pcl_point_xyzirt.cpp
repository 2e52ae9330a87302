// SPDX-License-Identifier: Apache-2.0
// sim/pcl.hpp's PointXYZIRT: LIO-SAM's point layout (x y z intensity ring time), registered with
// PCL, filled with each point's ring and its time after the frame stamp, from any family's frame.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include <pcl/common/io.h>  // getFieldsList

#include "sim/pcl.hpp"

namespace {

std::vector<sim::LidarPoint> points_with_time() {
  std::vector<sim::LidarPoint> points;
  for (int i = 0; i < 6; ++i) {
    sim::LidarPoint p{};
    p.x = 1.0f + static_cast<float>(i);
    p.y = -0.5f * static_cast<float>(i);
    p.z = 0.1f * static_cast<float>(i);
    p.intensity = static_cast<float>(7 * i);
    p.ring = static_cast<std::uint16_t>(15 - i);
    p.time_offset_ns = static_cast<std::uint32_t>(i) * 55'296;  // VLP-16 sequences
    points.push_back(p);
  }
  return points;
}

TEST(PclPointXyzirt, HasLioSamsFieldsInItsOrder) {
  EXPECT_EQ(pcl::getFieldsList(pcl::PointCloud<sim::PointXYZIRT>{}), "x y z intensity ring time");
}

TEST(PclPointXyzirt, LidarPointsKeepRingAndTimeAfterTheFrameStamp) {
  const auto points = points_with_time();
  pcl::PointCloud<sim::PointXYZIRT> cloud;
  sim::to_pcl(std::span<const sim::LidarPoint>(points), cloud);
  ASSERT_EQ(cloud.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(cloud[i].x, points[i].x);
    EXPECT_EQ(cloud[i].y, points[i].y);
    EXPECT_EQ(cloud[i].z, points[i].z);
    EXPECT_EQ(cloud[i].intensity, points[i].intensity);
    EXPECT_EQ(cloud[i].ring, points[i].ring);
    EXPECT_FLOAT_EQ(cloud[i].time, static_cast<float>(points[i].time_offset_ns * 1e-9));
  }
}

TEST(PclPointXyzirt, AFrameInABytesBufferConvertsFromItsLayout) {
  const auto points = points_with_time();
  std::vector<std::byte> bytes(points.size() * sizeof(sim::LidarPoint) + 1);
  std::memcpy(bytes.data() + 1, points.data(), points.size() * sizeof(sim::LidarPoint));  // unaligned
  sim::FrameInfo info;
  info.seq = 3;
  info.stamp_ns = 1'000'000'000;
  info.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, 100));
  info.size = points.size() * sizeof(sim::LidarPoint);
  pcl::PointCloud<sim::PointXYZIRT> cloud;
  ASSERT_TRUE(sim::to_pcl(sim::span<const std::byte>(bytes).subspan(1), info, cloud));
  ASSERT_EQ(cloud.size(), points.size());
  EXPECT_EQ(cloud[5].ring, 10);
  EXPECT_FLOAT_EQ(cloud[5].time, 5 * 55'296e-9f);
  EXPECT_EQ(cloud.header.stamp, 1'000'000U);
  // xyzi32 frames have no ring or time: zero.
  const float xyzi[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  info.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyzi32, 100));
  ASSERT_TRUE(sim::to_pcl(sim::span<const std::byte>(reinterpret_cast<const std::byte*>(xyzi), sizeof xyzi), info, cloud));
  ASSERT_EQ(cloud.size(), 2U);
  EXPECT_EQ(cloud[1].intensity, 8);
  EXPECT_EQ(cloud[1].ring, 0);
  EXPECT_EQ(cloud[1].time, 0);
}

}  // namespace
