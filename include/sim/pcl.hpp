// SPDX-License-Identifier: Apache-2.0
// Header-only adapter from a SIM LiDAR frame to a PCL cloud, for consumers that use PCL:
//
//   sim::Reader reader = *sim::Reader::open("/lidar_top");
//   std::vector<std::byte> buffer(reader.capacity());
//   sim::FrameInfo info;
//   pcl::PointCloud<pcl::PointXYZI> cloud;
//   if (reader.read_next(buffer, info, 1s) == sim::ReadStatus::new_frame)
//     sim::to_pcl(sim::span(buffer).first(info.size), info, cloud);
//
// For deskewing pipelines (LIO-SAM, FAST-LIO…) use sim::PointXYZIRT: LIO-SAM's PointXYZIRT
// layout (x y z intensity ring time), registered with PCL, filled from every LiDAR family:
// ring is LidarPoint::ring, time the point's seconds after the frame's stamp
// (LidarPoint::time_offset_ns · 1e-9, as the Velodyne ROS driver's "time" field).
//
// Points keep the sensor frame of the driver (for Hesai: y forward at azimuth 0, x right, z up;
// see sim/lidar_point.hpp). The cloud is resized in place, so reusing one cloud per stream
// allocates only when a frame is larger than any before it. Only this header needs PCL: the
// SIM library itself does not link it. Include it in as few translation units as possible, as
// PCL headers compile slowly.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>

#include "sim/layout.hpp"
#include "sim/lidar_point.hpp"
#include "sim/reader.hpp"
#include "sim/span.hpp"

namespace sim {

// x y z intensity ring time, field for field LIO-SAM's VelodynePointXYZIRT (and the Velodyne
// ROS driver's PointXYZIRT), so a cloud converts to theirs by field name.
// PCL_ADD_POINT4D declares an anonymous struct in an anonymous union, which -Wpedantic calls an
// extension; PCL's own point types do the same, but here it expands in our header, not PCL's.
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wgnu-anonymous-struct"
#pragma clang diagnostic ignored "-Wnested-anon-types"
#elif defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpedantic"
#endif
struct EIGEN_ALIGN16 PointXYZIRT {
  PCL_ADD_POINT4D;
  float intensity;
  std::uint16_t ring;
  float time;  // seconds after the frame's stamp
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
#if defined(__clang__)
#pragma clang diagnostic pop
#elif defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace pcl_detail {

// Whether a PCL point type has an intensity field (PointXYZI does, PointXYZ does not).
template <typename PointT, typename = void>
struct has_intensity : std::false_type {};
template <typename PointT>
struct has_intensity<PointT, std::void_t<decltype(std::declval<PointT&>().intensity)>> : std::true_type {};

template <typename PointT, typename = void>
struct has_ring : std::false_type {};
template <typename PointT>
struct has_ring<PointT, std::void_t<decltype(std::declval<PointT&>().ring)>> : std::true_type {};
template <typename PointT, typename = void>
struct has_time : std::false_type {};
template <typename PointT>
struct has_time<PointT, std::void_t<decltype(std::declval<PointT&>().time)>> : std::true_type {};

template <typename PointT>
void set_point(PointT& out, float x, float y, float z, float intensity, std::uint16_t ring = 0,
               std::uint32_t time_offset_ns = 0) noexcept {
  out.x = x;
  out.y = y;
  out.z = z;
  if constexpr (has_intensity<PointT>::value) out.intensity = intensity;
  if constexpr (has_ring<PointT>::value) out.ring = ring;
  if constexpr (has_time<PointT>::value) out.time = static_cast<float>(time_offset_ns * 1e-9);
}

template <typename PointT>
void set_point(PointT& out, const LidarPoint& p) noexcept {
  set_point(out, p.x, p.y, p.z, p.intensity, p.ring, p.time_offset_ns);
}

template <typename PointT>
void finish(pcl::PointCloud<PointT>& cloud, const FrameInfo* info) {
  bool dense = true;
  for (const PointT& p : cloud.points) {
    dense = dense && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  }
  cloud.is_dense = dense;
  if (info != nullptr) {
    cloud.header.stamp = static_cast<std::uint64_t>(info->stamp_ns / 1000);  // PCL stamps are µs
    cloud.header.seq = static_cast<std::uint32_t>(info->seq);
  }
}

}  // namespace pcl_detail

// The points of a lidar_point frame into a PointXYZI, PointXYZ or PointXYZIRT cloud (an unorganised cloud:
// height 1, width = number of points).
template <typename PointT>
void to_pcl(span<const LidarPoint> points, pcl::PointCloud<PointT>& cloud,
            const FrameInfo* info = nullptr) {
  cloud.resize(points.size());  // sets width = size, height = 1
  for (std::size_t i = 0; i < points.size(); ++i) {
    pcl_detail::set_point(cloud.points[i], points[i]);
  }
  pcl_detail::finish(cloud, info);
}

// Any SIM point frame (lidar_point, xyz32 or xyzi32) into a cloud, reading its type from the
// frame's layout. Returns false, leaving the cloud empty, for a frame that holds no points of a
// known type (an image stream, a raw-bytes stream), or whose size is not whole points.
template <typename PointT>
bool to_pcl(span<const std::byte> frame, const FrameInfo& info,
            pcl::PointCloud<PointT>& cloud) {
  cloud.clear();
  if (info.layout.kind != LayoutKind::points) return false;
  const std::uint32_t size = point_size(info.layout.points.type);
  if (size == 0 || frame.size() % size != 0) return false;
  const std::size_t count = frame.size() / size;
  switch (info.layout.points.type) {
    case PointType::lidar_point: {
      // The frame may not be aligned for LidarPoint (a caller's byte buffer): copy point-wise.
      cloud.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        LidarPoint p;
        std::memcpy(&p, frame.data() + i * size, sizeof p);
        pcl_detail::set_point(cloud.points[i], p);
      }
      break;
    }
    case PointType::xyz32:
    case PointType::xyzi32: {
      cloud.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        float v[4] = {0, 0, 0, 0};
        std::memcpy(v, frame.data() + i * size, size);
        pcl_detail::set_point(cloud.points[i], v[0], v[1], v[2], v[3]);
      }
      break;
    }
    default: return false;
  }
  pcl_detail::finish(cloud, &info);
  return true;
}

}  // namespace sim

POINT_CLOUD_REGISTER_POINT_STRUCT(sim::PointXYZIRT,
                                  (float, x, x)(float, y, y)(float, z, z)(float, intensity, intensity)(
                                      std::uint16_t, ring, ring)(float, time, time))
