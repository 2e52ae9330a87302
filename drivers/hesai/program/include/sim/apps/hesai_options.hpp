// SPDX-License-Identifier: Apache-2.0
// The decoder and stream options both Hesai programs take (sim_lidar_hesai, sim_replay_pcap),
// declared once so they spell, check and document them the same way. The values live here as
// plain options; stream_config() turns them into the stream library's configuration.
#pragma once

#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/lidar_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/os.hpp"

namespace sim::apps {

// With LidarWriterOptions: --checksum, --lock-memory, the sensor options, --cpu/--rt-priority.
struct HesaiStreamOptions : LidarWriterOptions {
  std::string stream = "/lidar_top";
  std::string model = "auto";  // a model name, or auto: detect it from the first packet
  std::string calibration;     // required (or fetched from the sensor by sim_lidar_hesai)
  std::string firetimes;       // empty: the built-in firing times
  double cut_azimuth = 0.0;
  std::optional<float> min_range;  // nullopt: the model's limits
  std::optional<float> max_range;
  bool keep_zero_distance = false;
  bool keep_identical_returns = false;
  float dual_return_threshold = 0.1F;
  bool partial_frames = false;
  bool firetime_azimuth_compensation = false;
  unsigned returns = 2;
  unsigned min_rpm = 600;
};

// Adds --stream --model --calibration --firetimes --cut-azimuth --min-range --max-range
// --keep-zero-distance --keep-identical-returns --dual-return-threshold --partial-frames
// --firetime-azimuth-compensation --returns --min-rpm --checksum --lock-memory --cpu
// --rt-priority and the sensor options (sim/apps/sensor_options.hpp). Every value is checked by parse(): a stream name, a model, a range.
void add_hesai_stream_options(CommandLine& cli, HesaiStreamOptions& options);

// The model given, or nullopt for auto (parse() has checked the name).
std::optional<hesai::Model> hesai_model(const HesaiStreamOptions& options);

// The stream library's configuration (assembler.model is set by whoever knows the model), with
// the sensor's description; an invalid_argument sentence (exit 2) when that is refused.
Expected<hesai::LidarStreamConfig> hesai_stream_config(const HesaiStreamOptions& options);

}  // namespace sim::apps
