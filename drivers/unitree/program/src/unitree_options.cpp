// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/unitree_options.hpp"

#include <chrono>

namespace sim::apps {

void add_unitree_stream_options(CommandLine& cli, UnitreeStreamOptions& o, SensorTimeOption sensor_time) {
  cli.add_option("--model", o.model, "L1 or L2 (also unitree-l1, unitree-l2)")
      .required()
      .check([](const std::string& text) { return unitree::model_problem(text); });
  cli.add_stream("--stream", o.stream, "SIM point stream, e.g. /lidar_top").required();
  cli.add_stream("--imu-stream", o.imu_stream, "SIM IMU stream (empty: <stream>.imu)");
  cli.add_flag("--no-imu", o.no_imu, "do not publish IMU samples");
  cli.add_option("--scan-packets", o.scan_packets, "packets per published scan (the SDKs' cloud_scan_num)")
      .in_range(1U, 1000U);
  if (sensor_time == SensorTimeOption::offered) {
    cli.add_flag("--sensor-time", o.sensor_time,
                 "stamp frames with the L2's own clock (its packets' times) instead of the time "
                 "the bytes arrived");
  }
  cli.add_option("--range-min", o.range_min, "drop points nearer than this (m)");
  cli.add_option("--range-max", o.range_max, "drop points farther than this (m)");
  add_lidar_writer_options(cli, o);
}

unitree::Model unitree_model(const UnitreeStreamOptions& o) {
  return unitree::parse_model(o.model).value_or(unitree::Model::l2);
}

Expected<unitree::LidarStreamConfig> unitree_stream_config(const UnitreeStreamOptions& o) {
  unitree::LidarStreamConfig config;
  config.stream = o.stream;
  if (!o.no_imu) config.imu_stream = o.imu_stream.empty() ? unitree::default_imu_stream(o.stream) : o.imu_stream;
  config.decoder.model = unitree_model(o);
  config.decoder.packets_per_scan = o.scan_packets;
  config.decoder.time_source = o.sensor_time ? unitree::TimeSource::sensor : unitree::TimeSource::host;
  config.decoder.range_min_m = o.range_min;
  config.decoder.range_max_m = o.range_max;
  // Readers can tell an idle driver (no data from the sensor) from a dead one.
  config.heartbeat_period = std::chrono::milliseconds(500);
  if (auto applied = apply_lidar_writer_options(config, o); !applied) return applied.error();
  return config;
}

}  // namespace sim::apps
