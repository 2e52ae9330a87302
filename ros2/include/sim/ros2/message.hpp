// SPDX-License-Identifier: Apache-2.0
// The three ROS 2 message types a SIM frame becomes (sensor_msgs/msg/PointCloud2, Image,
// CompressedImage), their names on the wire and their ros2msg schema texts.
//
// This is the ONE ROS 2 message layer of SIM: the DDS bridge, the Foxglove server and the MCAP
// recorder all serialize and parse through it, so a frame looks the same everywhere. It needs no
// ROS 2 and no DDS: the bytes are XCDR1 little-endian with the encapsulation header 00 01 00 00,
// exactly what rmw_fastrtps and rmw_cyclonedds put in an RTPS SerializedPayload (docs/bridge.md).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::ros2 {

enum class MessageType { point_cloud2, image, compressed_image };

// "sensor_msgs/msg/PointCloud2": the ROS name (schema name in MCAP and Foxglove).
std::string_view ros_type_name(MessageType type) noexcept;
// "sensor_msgs::msg::dds_::PointCloud2_": the DDS type name ROS 2 nodes match on.
std::string_view dds_type_name(MessageType type) noexcept;
// The ros2msg schema text: the message's .msg definition, then each dependency after a line of 80
// '=' and a "MSG: pkg/msg/Type" line (the rosbag2 / MCAP "ros2msg" schema encoding).
std::string_view ros2msg_schema(MessageType type) noexcept;

// The message a SIM stream of this layout is published as: points → PointCloud2, packed images →
// Image, mjpeg → CompressedImage. Raw byte streams have no ROS 2 message.
Expected<MessageType> message_type_for(const Layout& layout);

// "rt/lidar_top" for the ROS topic "/lidar_top": the DDS topic a ROS 2 node uses.
std::string dds_topic_name(std::string_view ros_topic);

// builtin_interfaces/msg/Time.
struct Time {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;

  // Nanoseconds since the epoch (negative stamps round down, so nanosec stays in [0, 1e9)).
  static Time from_ns(std::int64_t ns) noexcept;
  std::int64_t to_ns() const noexcept;
  friend bool operator==(const Time&, const Time&) = default;
};

// std_msgs/msg/Header. frame_id is borrowed: from the caller when encoding, from the message
// bytes when decoding.
struct Header {
  Time stamp{};
  std::string_view frame_id;
};

// sensor_msgs/msg/PointField datatypes (not Foxglove's numbering, which differs).
enum class PointFieldType : std::uint8_t {
  int8 = 1, uint8 = 2, int16 = 3, uint16 = 4, int32 = 5, uint32 = 6, float32 = 7, float64 = 8,
};
std::uint32_t size_of(PointFieldType type) noexcept;  // 0 for a value outside 1–8

struct PointField {
  std::string_view name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;  // a PointFieldType value when the message is well formed
  std::uint32_t count = 1;
};

// The fields a SIM point type is published with. For sim::LidarPoint (24 bytes):
//   x, y, z, intensity  FLOAT32 at 0, 4, 8, 12
//   time_stamp          UINT32 at 16: ns after header.stamp (nebula / Autoware PointXYZIRCAEDT name)
//   ring                UINT16 at 20: laser channel (velodyne, ouster, hesai drivers' name)
//   return_type         UINT8 at 22 (nebula / Autoware name)
// The reserved byte at 23 is padding and not described. xyz32 is x y z, xyzi32 adds intensity.
// Empty for PointType::unknown.
std::span<const PointField> point_fields(PointType type) noexcept;

// ROS image encoding of a SIM pixel format: "bgr8", "mono16", "bayer_rggb8", "yuv422" (uyvy) and
// "yuv422_yuy2" (yuyv; the names every ROS 2 release knows). Empty for mjpeg and unknown.
std::string_view ros_encoding(PixelFormat format) noexcept;
// The SIM pixel format of a ROS encoding; also accepts "uyvy", "yuyv", "8UC1", "8UC3" (bgr8),
// "8UC4" (bgra8) and "16UC1". PixelFormat::unknown when SIM has no such format.
PixelFormat pixel_format_of(std::string_view encoding) noexcept;

}  // namespace sim::ros2
