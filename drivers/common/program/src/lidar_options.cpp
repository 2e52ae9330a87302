// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/lidar_options.hpp"

namespace sim::apps {

void add_lidar_writer_options(CommandLine& cli, LidarWriterOptions& o) {
  cli.add_flag("--checksum", o.checksum, "add an XXH3 checksum to every frame, verified by readers");
  cli.add_flag("--lock-memory", o.lock_memory, "mlock the stream's shared memory");
  add_sensor_options(cli, o.sensor, SensorKind::lidar);
  cli.add_placement(o.placement);
}

}  // namespace sim::apps
