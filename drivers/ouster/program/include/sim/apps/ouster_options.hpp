// SPDX-License-Identifier: Apache-2.0
// The decoder and stream options both Ouster programs take (sim_lidar_ouster, sim_replay_pcap),
// declared once so they spell, check and document them the same way.
#pragma once

#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/lidar_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/ouster/lidar_stream.hpp"
#include "sim/os.hpp"

namespace sim::apps {

// With LidarWriterOptions: --checksum, --lock-memory, the sensor options, --cpu/--rt-priority.
struct OusterStreamOptions : LidarWriterOptions {
  std::string stream = "/lidar_top";
  std::string imu_stream;  // empty: <stream>.imu
  bool no_imu = false;
  std::string calibration;  // the sensor's metadata JSON
  std::string layout = "organized";
  std::string intensity = "auto";
  bool first_return_only = false;
  float min_range = 0;
  float max_range = 0;
  bool partial_frames = false;
};

// Adds --stream --imu-stream --no-imu --calibration --layout --intensity --first-return-only
// --min-range --max-range --partial-frames --checksum --lock-memory, the sensor options and
// --cpu/--rt-priority. Values are checked by parse().
void add_ouster_stream_options(CommandLine& cli, OusterStreamOptions& options);

// The stream library's configuration, with the sensor description from the sensor options
// (one sentence when they do not make one).
Expected<ouster::LidarStreamConfig> ouster_stream_config(const OusterStreamOptions& options);

}  // namespace sim::apps
