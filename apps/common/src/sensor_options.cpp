// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/sensor_options.hpp"

#include <cmath>

#include "sim/apps/camera_info_file.hpp"

namespace sim::apps {
namespace {

Error usage(std::string sentence) { return Error{ErrorCode::invalid_argument, std::move(sentence)}; }

std::string finite_problem(const std::string& text) {
  // CLI11 converts the text afterwards; this only refuses the conversions that succeed on
  // "nan" and "inf", which no mounting can be.
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (!std::isfinite(value)) return "'" + text + "' is not a finite number";
  } catch (const std::exception&) {
    // not a number at all: CLI11's own conversion error says so
  }
  return {};
}

}  // namespace

void add_sensor_options(CommandLine& cli, SensorOptions& options, SensorKind kind) {
  const auto frame = [](const std::string& name) { return frame_id_problem(name); };
  cli.add_text("--frame-id", options.frame_id, "the sensor's frame [the stream name without '/']",
               "FRAME", frame, "Sensor");
  cli.add_text("--parent-frame", options.parent_frame, "the frame the sensor is mounted in",
               "FRAME", frame, "Sensor");
  struct Axis {
    const char* name;
    std::optional<double>* value;
    const char* unit;
    const char* help;
  };
  const Axis axes[] = {
      {"--x", &options.x, "M", "mounting: translation along the parent's x, metres [0]"},
      {"--y", &options.y, "M", "mounting: translation along y, metres [0]"},
      {"--z", &options.z, "M", "mounting: translation along z, metres [0]"},
      {"--roll", &options.roll, "RAD", "mounting: rotation about x, radians [0]"},
      {"--pitch", &options.pitch, "RAD", "mounting: rotation about y, radians [0]"},
      {"--yaw", &options.yaw, "RAD",
       "mounting: rotation about z, radians [0] (applied first, as tf2's setRPY); any of "
       "--x … --yaw makes the mounting known"},
  };
  for (const Axis& axis : axes) {
    cli.add_number(axis.name, *axis.value, axis.help, axis.unit, finite_problem, "Sensor");
  }
  if (kind == SensorKind::camera) {
    cli.add_text("--camera-info", options.camera_info,
                 "the camera's calibration: a camera_calibration_parsers YAML file (as ROS's "
                 "cameracalibrator writes) or a file:// URL",
                 "FILE", {}, "Sensor");
    cli.add_path_option("camera-info");
  }
}

std::string default_frame_id(std::string_view stream) {
  std::string frame;
  for (const char ch : stream) {
    if (ch == '/' && frame.empty()) continue;
    frame += (ch == '.' || ch == '-') ? '_' : ch;
  }
  if (frame.empty() || (frame.front() >= '0' && frame.front() <= '9')) frame.insert(0, "sensor_");
  if (frame.size() > SensorInfo::kMaxName) frame.resize(SensorInfo::kMaxName);
  return frame;
}

Expected<SensorInfo> sensor_info_from(const SensorOptions& options, std::string_view stream) {
  SensorInfo info;
  info.frame_id = options.frame_id.empty() ? default_frame_id(stream) : options.frame_id;
  info.parent_frame = options.parent_frame;
  if (const std::string problem = frame_id_problem(info.frame_id); !problem.empty()) {
    return usage("the frame '" + info.frame_id + "': " + problem);
  }
  if (const std::string problem = frame_id_problem(info.parent_frame); !problem.empty()) {
    return usage("the parent frame '" + info.parent_frame + "': " + problem);
  }
  if (options.x || options.y || options.z || options.roll || options.pitch || options.yaw) {
    info.mounting = Mounting::from_xyz_rpy(options.x.value_or(0.0), options.y.value_or(0.0),
                                           options.z.value_or(0.0), options.roll.value_or(0.0),
                                           options.pitch.value_or(0.0), options.yaw.value_or(0.0));
  }
  if (!options.camera_info.empty()) {
    auto calibration = load_camera_info(options.camera_info);
    if (!calibration) return usage(calibration.error().message);
    info.calibration = std::move(calibration.value());
    auto path = camera_info_path(options.camera_info);
    info.calibration_source = "file://" + std::filesystem::absolute(*path).lexically_normal().string();
    if (info.calibration_source.size() > SensorInfo::kMaxSource) {
      // Too long to store: the file's name still says which calibration it was.
      info.calibration_source = path->filename().string();
    }
    // A path is the user's: odd characters in it (a newline) are shown as '?', never refused.
    info.calibration_source = sensor_text(info.calibration_source, SensorInfo::kMaxSource);
  }
  if (auto stored = check_sensor_info(info); !stored) return stored.error();
  return info;
}

Expected<void> check_calibration_size(const SensorInfo& info, std::uint32_t width,
                                      std::uint32_t height) {
  if (!info.calibration) return {};
  return sim::apps::check_calibration_size(*info.calibration, width, height);
}

Expected<void> check_sensor_info(const SensorInfo& info) {
  const std::string problem = sensor_info_problem(info);
  if (problem.empty()) return {};
  return usage(problem);
}

void describe_stamped_on_publish(SensorInfo& info) {
  info.time_base = TimeBase::host;
  info.time_sync = "replayed, stamped with this host's clock when published";
}

void describe_replayed_stamps(SensorInfo& info, bool restamped, RecordedClock recorded) {
  if (restamped) {
    info.time_base = TimeBase::host;
    info.time_sync = "replayed, restamped to this host's clock";
    return;
  }
  switch (recorded) {
    case RecordedClock::sensor:
      info.time_base = TimeBase::unknown;
      info.time_sync = "replayed with the recorded stamps (the sensor's clock; the recording does "
                       "not say whether it was synchronised)";
      return;
    case RecordedClock::sensor_with_position:
      info.time_base = TimeBase::unknown;
      info.time_sync = "replayed with the recorded stamps (the sensor's clock)";
      return;
    case RecordedClock::capturing_host:
      info.time_base = TimeBase::host;
      info.time_sync = "replayed with the recorded stamps (the recording host's clock when it "
                       "captured each packet)";
      return;
  }
}

}  // namespace sim::apps
