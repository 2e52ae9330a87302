// SPDX-License-Identifier: Apache-2.0
// The options every LiDAR stream ends with, in each family's options (drivers/hesai,
// drivers/velodyne, drivers/ouster: program/) and so in both of its programs (the live driver and
// sim_replay_pcap): --checksum, --lock-memory, the sensor description options and
// --cpu/--rt-priority, declared and applied once.
#pragma once

#include <utility>

#include "sim/apps/command_line.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/os.hpp"
#include "sim/result.hpp"

namespace sim::apps {

struct LidarWriterOptions {
  bool checksum = false;
  bool lock_memory = false;
  SensorOptions sensor;       // --frame-id, --parent-frame, --x … --yaw
  ThreadPlacement placement;  // --cpu, --rt-priority
};

// Adds --checksum, --lock-memory, the sensor options (SensorKind::lidar) and --cpu/--rt-priority.
void add_lidar_writer_options(CommandLine& cli, LidarWriterOptions& options);

// Sets a family config's checksum, lock_memory and sensor description (for its stream, which
// must be set); an invalid_argument sentence when the sensor options do not make one.
template <class Config>
Expected<void> apply_lidar_writer_options(Config& config, const LidarWriterOptions& options) {
  config.checksum = options.checksum;
  config.lock_memory = options.lock_memory;
  auto sensor = sensor_info_from(options.sensor, config.stream);
  if (!sensor) return sensor.error();
  config.sensor = std::move(sensor.value());
  return {};
}

}  // namespace sim::apps
