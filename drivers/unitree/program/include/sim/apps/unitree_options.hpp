// SPDX-License-Identifier: Apache-2.0
// The decoder and stream options every Unitree program takes (sim_lidar_unitree,
// sim_replay_serial, sim_replay_pcap), declared once so they spell, check and document them the
// same way. The values live here as plain options; unitree_stream_config() turns them into the
// stream library's configuration.
#pragma once

#include <cstdint>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/lidar_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/os.hpp"
#include "sim/result.hpp"
#include "sim/unitree/lidar_stream.hpp"

namespace sim::apps {

// With LidarWriterOptions: --checksum, --lock-memory, the sensor options, --cpu/--rt-priority.
struct UnitreeStreamOptions : LidarWriterOptions {
  std::string stream;      // required
  std::string model;       // L1 or L2 (also unitree-l1, unitree-l2); required
  std::string imu_stream;  // empty: <stream>.imu
  bool no_imu = false;
  std::uint32_t scan_packets = 18;  // the SDKs' cloud_scan_num
  bool sensor_time = false;         // the L2's own clock instead of the host time of the bytes
  float range_min = 0.0F;
  float range_max = 1.0e9F;
};

// Whether a program offers --sensor-time: the live driver and the pcap replay do; the serial
// replay stamps each scan when it publishes it (a byte recording holds no times of its own).
enum class SensorTimeOption { offered, not_offered };

// Adds --model --stream --imu-stream --no-imu --scan-packets [--sensor-time] --range-min
// --range-max --checksum --lock-memory, the sensor options and --cpu/--rt-priority. Every value
// is checked by parse(): a model, a stream name, a range.
void add_unitree_stream_options(CommandLine& cli, UnitreeStreamOptions& options,
                                SensorTimeOption sensor_time = SensorTimeOption::offered);

// The model given (parse() has checked it).
unitree::Model unitree_model(const UnitreeStreamOptions& options);

// The stream library's configuration (IMU stream "<stream>.imu" unless named or --no-imu,
// heartbeat every 500 ms), with the sensor's description; an invalid_argument sentence (exit 2)
// when that is refused.
Expected<unitree::LidarStreamConfig> unitree_stream_config(const UnitreeStreamOptions& options);

}  // namespace sim::apps
