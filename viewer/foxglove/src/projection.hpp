// SPDX-License-Identifier: Apache-2.0
// LiDAR points drawn into a camera image: the picture a person checks a calibration with. The
// points go from the LiDAR's frame to the camera's through the mountings the streams describe
// (up the parent frames to a common one and down again), then through the camera's pinhole
// model with its distortion (plumb_bob, rational_polynomial, equidistant) and K, as the raw
// image was taken (binning and ROI applied).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "foxglove_messages.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::foxglove {

// A rigid transform: p_out = rotation * p + translation (a Mounting maps child to parent).
struct Pose {
  std::array<double, 4> rotation{0, 0, 0, 1};  // unit quaternion x, y, z, w
  std::array<double, 3> translation{0, 0, 0};

  static Pose of(const Mounting& m) { return {m.rotation, m.translation}; }
  std::array<double, 3> apply(const std::array<double, 3>& p) const noexcept;
  Pose inverse() const noexcept;
  // (a * b).apply(p) == a.apply(b.apply(p)).
  friend Pose operator*(const Pose& a, const Pose& b) noexcept;
};

// The pose that maps points of frame `from` into frame `to`, through the mountings (each
// child in its parent). The error is one sentence naming the frame without a chain.
Expected<Pose> pose_between(const std::vector<FrameTransform>& mountings, std::string_view from,
                            std::string_view to);

// Where a point of the camera's frame (optical: x right, y down, z forward) lands in the raw
// image of `image_width` × `image_height`; nullopt behind the camera or outside the image.
std::optional<std::array<float, 2>> project_to_pixel(const CameraCalibration& calibration,
                                                     std::uint32_t image_width,
                                                     std::uint32_t image_height,
                                                     const std::array<double, 3>& point);

struct ProjectionResult {
  std::uint64_t points = 0;     // finite points in the frame
  std::uint64_t projected = 0;  // of them, drawn into the image
  float nearest_m = 0, farthest_m = 0;  // the colour scale: distance from the camera
};

// Draws every point of a LiDAR frame of `layout` into `bgr` (packed 8-bit BGR, width × height),
// coloured by its distance from the camera (near blue, far red), nearer points over farther.
ProjectionResult draw_projected_points(const PointLayout& layout, std::span<const std::byte> frame,
                                       const Pose& lidar_to_camera,
                                       const CameraCalibration& calibration, std::uint32_t width,
                                       std::uint32_t height, std::span<std::uint8_t> bgr);

}  // namespace sim::foxglove
