// SPDX-License-Identifier: Apache-2.0
// The two Foxglove message types sim_foxglove adds beside the frames, as ROS 2 messages in CDR
// (the encoding of every other channel): foxglove_msgs/msg/CameraCalibration, which Foxglove's
// image panel pairs with the image topic of the same namespace, and
// foxglove_msgs/msg/FrameTransforms, the mountings its 3D and image panels need. Both are
// "latched": sent to a client when it subscribes and again when they change.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/sensor_info.hpp"

namespace sim::foxglove {

inline constexpr std::string_view kCalibrationSchemaName = "foxglove_msgs/msg/CameraCalibration";
inline constexpr std::string_view kTransformsSchemaName = "foxglove_msgs/msg/FrameTransforms";
// The ros2msg schema texts (with their dependencies), as Foxglove's ROS 2 schemas define them.
std::string_view calibration_schema() noexcept;
std::string_view transforms_schema() noexcept;

// The topics of a camera stream: the image gets a namespace of its own so that Foxglove pairs
// it with its calibration (same prefix up to the last '/'), as the DDS bridge names them:
// "/camera_front" -> "/camera_front/image_raw" (CompressedImage: "/camera_front/compressed")
// and "/camera_front/camera_info".
std::string image_topic(std::string_view stream, bool compressed);
std::string calibration_topic(std::string_view stream);
// The frame a stream's messages are in: its sensor's frame_id, or else the stream name without
// its leading slash ("/lidar_top" -> "lidar_top").
std::string frame_of(std::string_view stream, const std::optional<SensorInfo>& sensor);

// Where every mounting goes (the tf2 name for transforms that do not change).
inline constexpr std::string_view kTransformsTopic = "/tf_static";

// The calibration of the picture a binned or cut camera sends (image_geometry's "reduced"
// camera): ROS calibrates the full sensor, and binning_x/y and the ROI say which part of it at
// which scale the image is; Foxglove's CameraCalibration has no such fields, so the picture's own
// K and P (fx / bx, (cx - x_offset) / bx, …) and size go instead (review turn 4 L3). Unchanged
// when there is neither binning nor an ROI.
CameraCalibration reduced_calibration(const CameraCalibration& calibration);

// foxglove_msgs/msg/CameraCalibration of `calibration` (reduced as above) in `frame_id`, stamped
// `stamp_ns`. The ROS "equidistant" model is Foxglove's "kannala_brandt"; a P of zeros (a file
// without a projection matrix) is sent as [K | 0], the monocular P, since Foxglove needs P's
// focal lengths.
std::vector<std::byte> encode_calibration(const CameraCalibration& calibration,
                                          std::string_view frame_id, std::int64_t stamp_ns);

// One mounting: `child` (a sensor's frame) in `parent`.
struct FrameTransform {
  std::string parent;
  std::string child;
  Mounting mounting;
  friend bool operator==(const FrameTransform&, const FrameTransform&) = default;
};
std::vector<std::byte> encode_transforms(const std::vector<FrameTransform>& transforms,
                                         std::int64_t stamp_ns);

}  // namespace sim::foxglove
