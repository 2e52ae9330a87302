// SPDX-License-Identifier: Apache-2.0
// YAML configuration of the camera drivers (config/camera/*.yaml). Keys mirror the command-line
// options; options given on the command line override the file.
#pragma once

#include <optional>
#include <string>

#include "sim/camera/aravis_capture.hpp"
#include "sim/camera/v4l2_capture.hpp"
#include "sim/os.hpp"
#include "sim/result.hpp"

namespace sim::camera {

using Placement = sim::ThreadPlacement;

// Reads `path` into `config` and `placement`, leaving keys the file does not mention unchanged.
// One sentence naming the file and the key on any error.
std::optional<Error> load_v4l2_config(const std::string& path, V4l2CaptureConfig& config,
                                      Placement& placement);

// The same for sim_camera_aravis: camera settings plus `features:`, a map of GenICam feature
// names to values applied in file order (ExposureAuto: "Off", GevSCPD: 1000, …).
std::optional<Error> load_aravis_config(const std::string& path, AravisCaptureConfig& config,
                                        Placement& placement);

}  // namespace sim::camera
