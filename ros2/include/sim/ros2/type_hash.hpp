// SPDX-License-Identifier: Apache-2.0
// RIHS01 type hashes: what ROS 2 (Iron and later) calls a message type's identity. A node puts
// "typehash=RIHS01_<64 hex>;" into the USER_DATA of each DDS endpoint, rosbag2 writes it into MCAP
// channel metadata (topic_type_hash), and rmw_zenoh matches on it.
//
// The hash is computed here as rosidl does it (rosidl_generator_type_description): SHA-256 of the
// JSON of the type's description (its fields, then every type it references, sorted by name;
// default values left out), written with ", " and ": " separators, hex with the prefix RIHS01_.
// tests/ros2 holds the result against the values rosidl generated for std_msgs/msg/Header and
// builtin_interfaces/msg/Time.
#pragma once

#include <string>
#include <string_view>

#include "sim/ros2/message.hpp"

namespace sim::ros2 {

// "RIHS01_f49fb3ae…" for a ROS type name such as "std_msgs/msg/Header", or empty for a type this
// layer does not describe. Described: builtin_interfaces/msg/Time, std_msgs/msg/Header,
// sensor_msgs/msg/{Image, CompressedImage, PointCloud2, PointField, CameraInfo,
// RegionOfInterest}, geometry_msgs/msg/{Vector3, Quaternion, Transform, TransformStamped},
// tf2_msgs/msg/TFMessage, rmw_dds_common/msg/{Gid, NodeEntitiesInfo, ParticipantEntitiesInfo},
// diagnostic_msgs/msg/{DiagnosticArray, DiagnosticStatus, KeyValue}.
// Computed once, then a lookup.
std::string_view rihs01_type_hash(std::string_view ros_type_name) noexcept;
std::string_view rihs01_type_hash(MessageType type) noexcept;

// The canonical JSON the hash is taken over (for tests and for checking against rosidl's output);
// empty for a type not described.
std::string type_description_json(std::string_view ros_type_name);

}  // namespace sim::ros2
