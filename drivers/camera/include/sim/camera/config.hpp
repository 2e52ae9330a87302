// SPDX-License-Identifier: Apache-2.0
// YAML configuration of the camera drivers (config/camera/*.yaml). Keys mirror the command-line
// options; options given on the command line override the file.
#pragma once

#include <optional>
#include <string>

#include "sim/camera/v4l2_capture.hpp"
#include "sim/result.hpp"

namespace sim::camera {

struct Placement {
  std::optional<int> cpu;
  std::optional<int> rt_priority;
};

// Reads `path` into `config` and `placement`, leaving keys the file does not mention unchanged.
// One sentence naming the file and the key on any error.
std::optional<Error> load_v4l2_config(const std::string& path, V4l2CaptureConfig& config,
                                      Placement& placement);

}  // namespace sim::camera
