// SPDX-License-Identifier: Apache-2.0
// The camera calibration file every ROS camera driver reads (camera_calibration_parsers YAML, as
// written by ROS's cameracalibrator and found through `camera_info_url`), read into and written
// from sim::CameraCalibration:
//
//   image_width: 640
//   image_height: 480
//   camera_name: front
//   camera_matrix: {rows: 3, cols: 3, data: [fx, 0, cx, 0, fy, cy, 0, 0, 1]}
//   distortion_model: plumb_bob          # missing: plumb_bob, as camera_calibration_parsers
//   distortion_coefficients: {rows: 1, cols: 5, data: [k1, k2, t1, t2, k3]}
//   rectification_matrix: {rows: 3, cols: 3, data: [...]}
//   projection_matrix: {rows: 3, cols: 4, data: [...]}
//   binning_x: 0                         # optional, as is roi: {x_offset, y_offset, height,
//   binning_y: 0                         #   width, do_rectify}
//
// A library of its own (sim::camera_info_file) so tools that only read or write calibrations
// (sim_dump) do not take the programs' command line with it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::apps {

// The calibration in `text`, or one sentence naming what is wrong (not YAML, a missing key, a
// matrix of the wrong size, a number that is not finite, a size of zero). `source` names the
// file in the sentence.
Expected<CameraCalibration> parse_camera_info(std::string_view text,
                                              std::string_view source = "the calibration file");

// `location` is a file name or a `file://` URL (camera_info_url's form; `file:///etc/cam.yaml`).
// Other URL schemes (package://) are refused with a sentence saying to give the file.
Expected<std::filesystem::path> camera_info_path(std::string_view location);

// Reads and parses the file at `location` (a name or a file:// URL).
Expected<CameraCalibration> load_camera_info(std::string_view location);

// Whether `calibration` fits images of `width` × `height`: the calibrated size, or its region of
// interest when one is given, divided by the binning. An invalid_argument sentence when not.
// (Here rather than in the options so the camera libraries check a reconnected camera too.)
Expected<void> check_calibration_size(const CameraCalibration& calibration, std::uint32_t width,
                                      std::uint32_t height);

// The file's text: the keys above, numbers written so they read back exactly. binning and roi
// are written only when they are not zero.
std::string format_camera_info(const CameraCalibration& calibration);

// Writes format_camera_info() to `file`; one sentence when it cannot.
Expected<void> save_camera_info(const std::filesystem::path& file,
                                const CameraCalibration& calibration);

}  // namespace sim::apps
