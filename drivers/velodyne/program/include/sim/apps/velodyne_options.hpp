// SPDX-License-Identifier: Apache-2.0
// The decoder and stream options both Velodyne programs take (sim_lidar_velodyne,
// sim_replay_pcap), declared once so they spell, check and document them the same way.
#pragma once

#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/lidar_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/os.hpp"
#include "sim/velodyne/lidar_stream.hpp"

namespace sim::apps {

// With LidarWriterOptions: --checksum, --lock-memory, the sensor options, --cpu/--rt-priority.
struct VelodyneStreamOptions : LidarWriterOptions {
  std::string stream = "/lidar_top";
  std::string model = "auto";  // a model name, or auto: from the first packet's product ID
  std::string calibration;     // YAML or db.xml (required)
  double cut_azimuth = 0.0;
  std::optional<float> min_range;
  std::optional<float> max_range;
  std::string returns = "both";  // both, last, strongest (dual-return packets)
  bool keep_identical_returns = false;
  std::string interpolation = "firing-time";  // firing-time, nebula
  std::string cut_by = "point";               // point, packet (nebula)
  bool partial_frames = false;
  unsigned min_rpm = 300;
};

// Adds --stream --model --calibration --cut-azimuth --min-range --max-range --returns
// --keep-identical-returns --interpolation --cut-by --partial-frames --min-rpm --checksum
// --lock-memory, the sensor options and --cpu/--rt-priority. Values are checked by parse().
void add_velodyne_stream_options(CommandLine& cli, VelodyneStreamOptions& options);

// The model given, or nullopt for auto.
std::optional<velodyne::Model> velodyne_model(const VelodyneStreamOptions& options);

// The stream library's configuration with the sensor description (one sentence when the sensor
// options do not make one). assembler.model is set by whoever knows the model.
Expected<velodyne::LidarStreamConfig> velodyne_stream_config(const VelodyneStreamOptions& options);

}  // namespace sim::apps
