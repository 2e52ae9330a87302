// SPDX-License-Identifier: Apache-2.0
// include/sim/pcl.hpp: a SIM frame into pcl::PointCloud<PointXYZI> / <PointXYZ>.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "sim/pcl.hpp"

namespace {

std::vector<sim::LidarPoint> sample_points() {
  std::vector<sim::LidarPoint> points;
  for (int i = 0; i < 5; ++i) {
    sim::LidarPoint p{};
    p.x = 1.5f * static_cast<float>(i);
    p.y = -2.0f + static_cast<float>(i);
    p.z = 0.25f * static_cast<float>(i);
    p.intensity = static_cast<float>(10 * i);
    p.ring = static_cast<std::uint16_t>(i);
    points.push_back(p);
  }
  return points;
}

sim::FrameInfo info_for(sim::PointType type, std::size_t points) {
  sim::FrameInfo info;
  info.seq = 42;
  info.stamp_ns = 1'593'086'530'075'474'632;
  info.layout = sim::Layout::of(sim::PointLayout::of(type, 100));
  info.size = points * sim::point_size(type);
  return info;
}

TEST(PclAdapter, LidarPointsToXyziAndXyz) {
  const auto points = sample_points();
  pcl::PointCloud<pcl::PointXYZI> xyzi;
  pcl::PointCloud<pcl::PointXYZ> xyz;
  const sim::FrameInfo info = info_for(sim::PointType::lidar_point, points.size());
  sim::to_pcl(std::span<const sim::LidarPoint>(points), xyzi, &info);
  sim::to_pcl(std::span<const sim::LidarPoint>(points), xyz);
  ASSERT_EQ(xyzi.size(), points.size());
  ASSERT_EQ(xyz.size(), points.size());
  EXPECT_EQ(xyzi.width, points.size());
  EXPECT_EQ(xyzi.height, 1u);
  EXPECT_TRUE(xyzi.is_dense);
  EXPECT_EQ(xyzi.header.stamp, 1'593'086'530'075'474u);  // PCL stamps are microseconds
  EXPECT_EQ(xyzi.header.seq, 42u);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(xyzi[i].x, points[i].x);
    EXPECT_EQ(xyzi[i].y, points[i].y);
    EXPECT_EQ(xyzi[i].z, points[i].z);
    EXPECT_EQ(xyzi[i].intensity, points[i].intensity);
    EXPECT_EQ(xyz[i].x, points[i].x);
    EXPECT_EQ(xyz[i].z, points[i].z);
  }
  // Reusing the cloud for a smaller frame shrinks it.
  sim::to_pcl(std::span<const sim::LidarPoint>(points).first(2), xyzi);
  EXPECT_EQ(xyzi.size(), 2u);
  EXPECT_EQ(xyzi.width, 2u);
}

TEST(PclAdapter, FrameBytesOfEveryPointType) {
  const auto points = sample_points();
  // Unaligned on purpose: a reader's byte buffer need not be aligned for LidarPoint.
  std::vector<std::byte> storage(points.size() * sizeof(sim::LidarPoint) + 1);
  std::memcpy(storage.data() + 1, points.data(), points.size() * sizeof(sim::LidarPoint));
  const auto frame = std::span<const std::byte>(storage).subspan(1);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  ASSERT_TRUE(sim::to_pcl(frame, info_for(sim::PointType::lidar_point, points.size()), cloud));
  ASSERT_EQ(cloud.size(), points.size());
  EXPECT_EQ(cloud[3].intensity, 30.0f);
  EXPECT_EQ(cloud[3].y, points[3].y);

  std::vector<float> xyzi_values = {1, 2, 3, 4, 5, 6, 7, 8};
  ASSERT_TRUE(sim::to_pcl(std::as_bytes(std::span(xyzi_values)), info_for(sim::PointType::xyzi32, 2), cloud));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud[1].x, 5.0f);
  EXPECT_EQ(cloud[1].intensity, 8.0f);

  pcl::PointCloud<pcl::PointXYZ> xyz;
  std::vector<float> xyz_values = {1, 2, 3, 4, 5, 6};
  ASSERT_TRUE(sim::to_pcl(std::as_bytes(std::span(xyz_values)), info_for(sim::PointType::xyz32, 2), xyz));
  EXPECT_EQ(xyz[1].z, 6.0f);
}

TEST(PclAdapter, RefusesFramesThatAreNotWholePoints) {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  cloud.resize(3);
  std::vector<std::byte> bytes(25);  // one LidarPoint and a byte
  EXPECT_FALSE(sim::to_pcl(std::span<const std::byte>(bytes), info_for(sim::PointType::lidar_point, 1), cloud));
  EXPECT_TRUE(cloud.empty());
  sim::FrameInfo image;
  image.layout = sim::Layout::of(sim::ImageLayout::packed(4, 4, sim::PixelFormat::mono8));
  EXPECT_FALSE(sim::to_pcl(std::span<const std::byte>(bytes).first(16), image, cloud));
  EXPECT_FALSE(sim::to_pcl(std::span<const std::byte>(bytes), sim::FrameInfo{}, cloud));
}

}  // namespace
