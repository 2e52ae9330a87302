// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/ouster_options.hpp"

namespace sim::apps {
namespace {

std::optional<ouster::IntensityField> parse_intensity(const std::string& name) {
  if (name == "auto") return ouster::IntensityField::automatic;
  if (name == "signal") return ouster::IntensityField::signal;
  if (name == "reflectivity") return ouster::IntensityField::reflectivity;
  if (name == "near-ir") return ouster::IntensityField::near_ir;
  return std::nullopt;
}

}  // namespace

void add_ouster_stream_options(CommandLine& cli, OusterStreamOptions& o) {
  cli.add_stream("--stream", o.stream, "SIM stream to publish the points on");
  cli.add_stream("--imu-stream", o.imu_stream, "SIM stream for the IMU samples [<stream>.imu]");
  cli.add_flag("--no-imu", o.no_imu, "publish no IMU stream");
  cli.add_option("--calibration,--metadata", o.calibration,
                 "the sensor's metadata JSON (what http://SENSOR/api/v1/sensor/metadata returns)")
      .type_name("FILE.json");
  cli.add_option("--layout", o.layout,
                 "organized: H x W points per return, destaggered, no return at the origin; "
                 "dense: only points with a return")
      .one_of({"organized", "dense"});
  cli.add_option("--intensity", o.intensity,
                 "the channel in each point's intensity: signal, reflectivity, near-ir, or auto "
                 "(signal, reflectivity for the RNG15 profiles)")
      .one_of({"auto", "signal", "reflectivity", "near-ir"});
  cli.add_flag("--first-return-only", o.first_return_only, "dual-return profiles: drop the second return");
  cli.add_option("--min-range", o.min_range, "returns closer than this (m) count as none")
      .non_negative();
  cli.add_option("--max-range", o.max_range, "returns farther than this (m) count as none; 0: no limit")
      .non_negative();
  cli.add_flag("--partial-frames", o.partial_frames,
               "also publish frames that did not start at the first column (start, gaps)");
  add_lidar_writer_options(cli, o);
}

Expected<ouster::LidarStreamConfig> ouster_stream_config(const OusterStreamOptions& o) {
  ouster::LidarStreamConfig config;
  config.stream = o.stream;
  if (!o.no_imu) config.imu_stream = o.imu_stream.empty() ? ouster::default_imu_stream(o.stream) : o.imu_stream;
  config.assembler.layout = o.layout == "dense" ? ouster::CloudLayout::dense : ouster::CloudLayout::organized;
  config.assembler.intensity = parse_intensity(o.intensity).value_or(ouster::IntensityField::automatic);
  config.assembler.first_return_only = o.first_return_only;
  config.assembler.min_range_m = o.min_range;
  config.assembler.max_range_m = o.max_range;
  config.assembler.emit_partial_frames = o.partial_frames;
  if (auto applied = apply_lidar_writer_options(config, o); !applied) return applied.error();
  return config;
}

}  // namespace sim::apps
