// SPDX-License-Identifier: Apache-2.0
// The options every driver and replay program takes to describe its sensor (issue 21), with the
// names of ROS 2's static_transform_publisher:
//   --frame-id NAME         the sensor's frame [the stream name without '/', '.' and '-' as '_']
//   --parent-frame NAME     the frame it is mounted in [base_link]
//   --x --y --z M           the mounting's translation, metres
//   --roll --pitch --yaw R  its rotation, radians (yaw about z, then pitch about y, then roll
//                           about x, as tf2's setRPY); giving any of the six makes the mounting
//                           known, the others are 0
//   --camera-info FILE      cameras: the camera_calibration_parsers YAML (or a file:// URL)
// The same keys in a --config file (frame_id, parent_frame, x, …, camera_info; a relative
// camera_info is relative to the config file's folder).
//
//   sim::apps::SensorOptions sensor;
//   sim::apps::add_sensor_options(cli, sensor, sim::apps::SensorKind::camera);
//   ...parse...
//   auto info = sim::apps::sensor_info_from(sensor, stream_name);       // loads the calibration
//   if (!info) return cli.fail(info.error());                            // exit 2, one sentence
//   info->time_base = sim::TimeBase::host;                               // what the driver knows
//   if (auto fits = sim::apps::check_calibration_size(*info, w, h); !fits) return cli.fail(...);
//   spec.sensor = *info;                                                 // then create the stream
//
// Every error is an ErrorCode::invalid_argument sentence: CommandLine::fail(error) exits 2.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "sim/apps/command_line.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::apps {

enum class SensorKind {
  lidar,   // frame and mounting
  camera,  // frame, mounting and --camera-info
};

struct SensorOptions {
  std::string frame_id;  // empty: from the stream name
  std::string parent_frame = "base_link";
  std::optional<double> x, y, z, roll, pitch, yaw;
  std::string camera_info;  // a file name or file:// URL; empty: no calibration
};

// Adds the options above to `cli` (and camera_info to the config file's path options). Frame
// names and numbers are checked while parsing: a bad one is a usage error (exit 2).
void add_sensor_options(CommandLine& cli, SensorOptions& options, SensorKind kind);

// The frame a stream's sensor gets when --frame-id is not given: "/camera.front-left" ->
// "camera_front_left" (the DDS bridge names its frames the same way).
std::string default_frame_id(std::string_view stream);

// The description the options give: frame, parent, mounting (when any of the six numbers was
// given) and the calibration read from --camera-info. One sentence when the file cannot be read
// or parsed, or when the result cannot be stored (sim::sensor_info_problem).
Expected<SensorInfo> sensor_info_from(const SensorOptions& options, std::string_view stream);

// Whether a calibration fits images of `width` × `height`: the calibrated size, or its region
// of interest when one is given, divided by the binning. Nothing to check without a calibration.
Expected<void> check_calibration_size(const SensorInfo& info, std::uint32_t width,
                                      std::uint32_t height);

// sim::sensor_info_problem as an Expected, for a description completed by the driver (identity,
// time base) just before it creates the stream.
Expected<void> check_sensor_info(const SensorInfo& info);

// For a replay that stamps each frame with this host's clock as it publishes it (sim_replay_video,
// sim_replay_serial): the host time base, and the one time_sync sentence that says so.
void describe_stamped_on_publish(SensorInfo& info);

// The clock a recording's stamps are in, for a replay that keeps them (sim_replay_pcap without
// --restamp).
enum class RecordedClock {
  sensor,                // the sensor's, from its packets; the recording does not show whether it
                         // was synchronised (Hesai, Ouster): time base unknown
  sensor_with_position,  // the sensor's, and the recording's own packets show its synchronisation
                         // (Velodyne position packets): time base unknown until the stream reads
                         // them (velodyne::StampClock::sensor_recorded)
  capturing_host,        // the recording host's, when it captured each packet (Unitree): host
};

// For a replay of a recording (sim_replay_pcap), one sentence per situation for every family.
// Restamped (--restamp): the stamps are this host's clock as the frames are replayed
// (TimeBase::host, "replayed, restamped to this host's clock"). Otherwise they are the recorded
// stamps, in the `recorded` clock: "replayed with the recorded stamps (the sensor's clock; …)".
void describe_replayed_stamps(SensorInfo& info, bool restamped, RecordedClock recorded);

}  // namespace sim::apps
