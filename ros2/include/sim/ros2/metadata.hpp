// SPDX-License-Identifier: Apache-2.0
// The messages that travel beside the frames: sensor_msgs/msg/CameraInfo (a camera's calibration,
// one per image with the image's stamp and frame_id, on the sibling topic .../camera_info) and
// tf2_msgs/msg/TFMessage (the sensors' mountings on /tf_static). Same XCDR1 little-endian bytes
// as the frame messages (message.hpp), built from and parsed into sim::SensorInfo's parts, so the
// bridge, MCAP and Foxglove agree on them.
//
// These are small and rare (a calibration or a mounting changes seldom): they are built into a
// std::vector once; a publisher restamps the same bytes per frame with restamp().
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "sim/result.hpp"
#include "sim/ros2/message.hpp"
#include "sim/sensor_info.hpp"

namespace sim::ros2 {

inline constexpr std::string_view camera_info_type_name = "sensor_msgs/msg/CameraInfo";
inline constexpr std::string_view camera_info_dds_type_name = "sensor_msgs::msg::dds_::CameraInfo_";
inline constexpr std::string_view tf_message_type_name = "tf2_msgs/msg/TFMessage";
inline constexpr std::string_view tf_message_dds_type_name = "tf2_msgs::msg::dds_::TFMessage_";

// ros2msg schema texts (as ros2msg_schema() in message.hpp) for MCAP and Foxglove channels.
std::string_view camera_info_schema() noexcept;
std::string_view tf_message_schema() noexcept;

// Most transforms one TFMessage may carry here, and most distortion coefficients a CameraInfo.
inline constexpr std::size_t max_transforms = 1024;
inline constexpr std::size_t max_distortion_coefficients = CameraCalibration::kMaxDistortion;

// "/cam/front/camera_info" for "/cam/front/image_raw" and "/cam/front/image_raw/compressed": the
// sibling topic image_transport's CameraSubscriber and Foxglove pair with an image topic (its
// last name token replaced, after the "/compressed" of a compressed image's topic).
std::string camera_info_topic_for(std::string_view image_topic);

// CameraInfo of `calibration` (camera_name is not on the wire). An error for a frame_id that a
// header cannot carry or more than max_distortion_coefficients coefficients.
Expected<std::vector<std::byte>> encode_camera_info(const Header& header,
                                                    const CameraCalibration& calibration);

struct CameraInfoView {
  Header header;  // frame_id borrows the message bytes
  CameraCalibration calibration;  // camera_name empty
};
Expected<CameraInfoView> decode_camera_info(std::span<const std::byte> message);

// geometry_msgs/msg/TransformStamped: `child_frame_id` mounted in header.frame_id.
struct TransformStamped {
  Header header;  // frame_id: the parent frame
  std::string_view child_frame_id;
  Mounting transform;
};

// The transform of a sensor's mounting (parent_frame → frame_id), or nullopt when the mounting is
// not known. Borrows info's strings.
std::optional<TransformStamped> mounting_transform(const SensorInfo& info, Time stamp);

Expected<std::vector<std::byte>> encode_tf_message(std::span<const TransformStamped> transforms);
// Transforms borrow the message bytes. An error past max_transforms.
Expected<std::vector<TransformStamped>> decode_tf_message(std::span<const std::byte> message);

// Rewrites header.stamp of a serialized message whose first field is a std_msgs/Header (every
// message here): the stamp is at bytes 4–11. False if the message is shorter.
bool restamp(std::span<std::byte> message, Time stamp) noexcept;

}  // namespace sim::ros2
