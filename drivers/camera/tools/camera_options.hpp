// SPDX-License-Identifier: Apache-2.0
// The command lines of sim_camera_v4l2 and sim_camera_aravis on the programs' shared library:
// every option can also come from the --config YAML file under its long name (config/camera/),
// and the command line wins over the file. Kept apart from the programs so tests parse them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/camera/aravis_capture.hpp"
#include "sim/camera/v4l2_capture.hpp"
#include "sim/timing/clock_check.hpp"
#include "sim/timing/host_clock.hpp"

namespace sim::camera {

// --clock-offset-ok-ms and --clock-spread-warn-ms: the camera's clock tolerance
// (camera_clock_tolerance()), and --ptp4l-socket: the host's clock the check judges against.
struct ClockToleranceOptions {
  timing::ClockTolerance tolerance = camera_clock_tolerance();
  double offset_ok_ms = 250;
  double spread_warn_ms = 50;
  timing::HostClockOptions host{};
};

struct V4l2Options {
  V4l2CaptureConfig config;
  ThreadPlacement placement;
  std::string format = "auto";
  std::string output = "bgr8";
  std::string timestamps = "device";
  std::vector<std::string> controls;  // name=value
  std::uint32_t frame_timeout_ms = 3000;
  std::uint32_t retry_period_ms = 500;
  bool list_formats = false;
  bool list_controls = false;
  bool quiet = false;
  apps::SensorOptions sensor;  // --frame-id … --camera-info
  ClockToleranceOptions clock;
};

void add_v4l2_options(apps::CommandLine& cli, V4l2Options& options);
// After parsing: the text options into `options.config` (the sensor options, with the calibration
// file read, into config.sensor); one sentence for a value or a file that is wrong.
std::optional<std::string> finish_v4l2_options(V4l2Options& options);

struct AravisOptions {
  AravisCaptureConfig config;
  ThreadPlacement placement;
  std::string output = "bgr8";
  std::vector<std::int32_t> roi;        // x y width height
  std::vector<std::string> features;    // Name=value
  std::uint32_t retry_period_ms = 1000;
  bool list = false;
  bool quiet = false;
  apps::SensorOptions sensor;  // --frame-id … --camera-info
  ClockToleranceOptions clock;
};

void add_aravis_options(apps::CommandLine& cli, AravisOptions& options);
std::optional<std::string> finish_aravis_options(AravisOptions& options);

}  // namespace sim::camera
