// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/message.hpp"

#include <array>
#include <cstddef>

#include "sim/lidar_point.hpp"

namespace sim::ros2 {

std::string_view ros_type_name(MessageType type) noexcept {
  switch (type) {
    case MessageType::point_cloud2: return "sensor_msgs/msg/PointCloud2";
    case MessageType::image: return "sensor_msgs/msg/Image";
    case MessageType::compressed_image: return "sensor_msgs/msg/CompressedImage";
  }
  return {};
}

std::string_view dds_type_name(MessageType type) noexcept {
  switch (type) {
    case MessageType::point_cloud2: return "sensor_msgs::msg::dds_::PointCloud2_";
    case MessageType::image: return "sensor_msgs::msg::dds_::Image_";
    case MessageType::compressed_image: return "sensor_msgs::msg::dds_::CompressedImage_";
  }
  return {};
}

namespace {

// The .msg texts of ros2/common_interfaces and ros2/rcl_interfaces without their comments. The
// header field is written fully qualified (std_msgs/msg/Header, as its MSG: line): Foxglove's
// and Lichtblick's ros2msg parser (@foxglove/rosmsg) matches qualified names exactly and
// rejects the short "std_msgs/Header" against "MSG: std_msgs/msg/Header".
#define SIM_ROS2_SEPARATOR \
  "================================================================================\n"
#define SIM_ROS2_HEADER_DEPS                   \
  SIM_ROS2_SEPARATOR                           \
  "MSG: std_msgs/msg/Header\n"                 \
  "builtin_interfaces/Time stamp\n"            \
  "string frame_id\n" SIM_ROS2_SEPARATOR       \
  "MSG: builtin_interfaces/msg/Time\n"         \
  "int32 sec\n"                                \
  "uint32 nanosec\n"

constexpr std::string_view point_cloud2_schema =
    "std_msgs/msg/Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "PointField[] fields\n"
    "bool is_bigendian\n"
    "uint32 point_step\n"
    "uint32 row_step\n"
    "uint8[] data\n"
    "bool is_dense\n" SIM_ROS2_HEADER_DEPS SIM_ROS2_SEPARATOR
    "MSG: sensor_msgs/msg/PointField\n"
    "uint8 INT8 = 1\n"
    "uint8 UINT8 = 2\n"
    "uint8 INT16 = 3\n"
    "uint8 UINT16 = 4\n"
    "uint8 INT32 = 5\n"
    "uint8 UINT32 = 6\n"
    "uint8 FLOAT32 = 7\n"
    "uint8 FLOAT64 = 8\n"
    "string name\n"
    "uint32 offset\n"
    "uint8 datatype\n"
    "uint32 count\n";

constexpr std::string_view image_schema =
    "std_msgs/msg/Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "string encoding\n"
    "uint8 is_bigendian\n"
    "uint32 step\n"
    "uint8[] data\n" SIM_ROS2_HEADER_DEPS;

constexpr std::string_view compressed_image_schema =
    "std_msgs/msg/Header header\n"
    "string format\n"
    "uint8[] data\n" SIM_ROS2_HEADER_DEPS;

#undef SIM_ROS2_HEADER_DEPS
#undef SIM_ROS2_SEPARATOR

constexpr auto f32 = static_cast<std::uint8_t>(PointFieldType::float32);
constexpr std::array<PointField, 7> lidar_point_fields{{
    {"x", offsetof(LidarPoint, x), f32, 1},
    {"y", offsetof(LidarPoint, y), f32, 1},
    {"z", offsetof(LidarPoint, z), f32, 1},
    {"intensity", offsetof(LidarPoint, intensity), f32, 1},
    {"time_stamp", offsetof(LidarPoint, time_offset_ns),
     static_cast<std::uint8_t>(PointFieldType::uint32), 1},
    {"ring", offsetof(LidarPoint, ring), static_cast<std::uint8_t>(PointFieldType::uint16), 1},
    {"return_type", offsetof(LidarPoint, return_index),
     static_cast<std::uint8_t>(PointFieldType::uint8), 1},
}};

}  // namespace

std::string_view ros2msg_schema(MessageType type) noexcept {
  switch (type) {
    case MessageType::point_cloud2: return point_cloud2_schema;
    case MessageType::image: return image_schema;
    case MessageType::compressed_image: return compressed_image_schema;
  }
  return {};
}

Expected<MessageType> message_type_for(const Layout& layout) {
  switch (layout.kind) {
    case LayoutKind::points: return MessageType::point_cloud2;
    case LayoutKind::image:
      return layout.image.format == PixelFormat::mjpeg ? MessageType::compressed_image
                                                       : MessageType::image;
    case LayoutKind::bytes: break;
  }
  return Error{ErrorCode::invalid_argument,
               "the stream carries raw bytes, which have no ROS 2 message; publish images or points "
               "with a layout to bridge them"};
}

std::string dds_topic_name(std::string_view ros_topic) {
  std::string out = "rt";
  if (ros_topic.empty() || ros_topic.front() != '/') out += '/';
  out += ros_topic;
  return out;
}

Time Time::from_ns(std::int64_t ns) noexcept {
  constexpr std::int64_t billion = 1'000'000'000;
  std::int64_t sec = ns / billion;
  std::int64_t rem = ns % billion;
  if (rem < 0) {
    rem += billion;
    --sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(rem)};
}

std::int64_t Time::to_ns() const noexcept {
  return std::int64_t{sec} * 1'000'000'000 + std::int64_t{nanosec};
}

std::uint32_t size_of(PointFieldType type) noexcept {
  switch (type) {
    case PointFieldType::int8:
    case PointFieldType::uint8: return 1;
    case PointFieldType::int16:
    case PointFieldType::uint16: return 2;
    case PointFieldType::int32:
    case PointFieldType::uint32:
    case PointFieldType::float32: return 4;
    case PointFieldType::float64: return 8;
  }
  return 0;
}

std::span<const PointField> point_fields(PointType type) noexcept {
  switch (type) {
    case PointType::xyz32: return std::span(lidar_point_fields).first(3);
    case PointType::xyzi32: return std::span(lidar_point_fields).first(4);
    case PointType::lidar_point: return lidar_point_fields;
    case PointType::unknown: break;
  }
  return {};
}

std::string_view ros_encoding(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::mono8: return "mono8";
    case PixelFormat::mono16: return "mono16";
    case PixelFormat::bgr8: return "bgr8";
    case PixelFormat::rgb8: return "rgb8";
    case PixelFormat::bgra8: return "bgra8";
    case PixelFormat::rgba8: return "rgba8";
    case PixelFormat::yuyv: return "yuv422_yuy2";
    case PixelFormat::uyvy: return "yuv422";
    case PixelFormat::bayer_rggb8: return "bayer_rggb8";
    case PixelFormat::bayer_bggr8: return "bayer_bggr8";
    case PixelFormat::bayer_gbrg8: return "bayer_gbrg8";
    case PixelFormat::bayer_grbg8: return "bayer_grbg8";
    case PixelFormat::mjpeg:
    case PixelFormat::unknown: break;
  }
  return {};
}

PixelFormat pixel_format_of(std::string_view encoding) noexcept {
  struct Name {
    std::string_view name;
    PixelFormat format;
  };
  static constexpr std::array<Name, 18> names{{
      {"mono8", PixelFormat::mono8},
      {"8UC1", PixelFormat::mono8},
      {"mono16", PixelFormat::mono16},
      {"16UC1", PixelFormat::mono16},
      {"bgr8", PixelFormat::bgr8},
      {"8UC3", PixelFormat::bgr8},  // OpenCV's channel order, as cv_bridge assumes
      {"rgb8", PixelFormat::rgb8},
      {"bgra8", PixelFormat::bgra8},
      {"8UC4", PixelFormat::bgra8},
      {"rgba8", PixelFormat::rgba8},
      {"yuv422_yuy2", PixelFormat::yuyv},
      {"yuyv", PixelFormat::yuyv},
      {"yuv422", PixelFormat::uyvy},
      {"uyvy", PixelFormat::uyvy},
      {"bayer_rggb8", PixelFormat::bayer_rggb8},
      {"bayer_bggr8", PixelFormat::bayer_bggr8},
      {"bayer_gbrg8", PixelFormat::bayer_gbrg8},
      {"bayer_grbg8", PixelFormat::bayer_grbg8},
  }};
  for (const Name& n : names) {
    if (n.name == encoding) return n.format;
  }
  return PixelFormat::unknown;
}

}  // namespace sim::ros2
