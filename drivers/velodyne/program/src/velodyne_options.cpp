// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/velodyne_options.hpp"

namespace sim::apps {
namespace {

std::string model_problem(const std::string& name) {
  if (name == "auto" || velodyne::parse_model(name)) return {};
  return "unknown model '" + name + "'; use one of " + std::string(velodyne::model_names()) + " or auto";
}

}  // namespace

void add_velodyne_stream_options(CommandLine& cli, VelodyneStreamOptions& o) {
  cli.add_stream("--stream", o.stream, "SIM stream to publish");
  cli.add_option("--model", o.model,
                 "sensor model (" + std::string(velodyne::model_names()) +
                     "), or auto to detect it from the first packet")
      .type_name("MODEL")
      .check(model_problem);
  cli.add_option("--calibration", o.calibration,
                 "the sensor's calibration: ros-drivers/velodyne YAML (nominal tables in "
                 "/usr/share/sim/velodyne) or an HDL-64E's db.xml (required)")
      .type_name("FILE");
  cli.add_option("--cut-azimuth", o.cut_azimuth, "azimuth in degrees where one revolution ends and the next begins")
      .in_range(0.0, 359.99);
  cli.add_option_function<float>("--min-range", [&o](float v) { o.min_range = v; },
                                 "drop points closer than this, metres [0.3]")
      .type_name("FLOAT")
      .non_negative();
  cli.add_option_function<float>("--max-range", [&o](float v) { o.max_range = v; },
                                 "drop points farther than this, metres [300]")
      .type_name("FLOAT")
      .positive();
  cli.add_option("--returns", o.returns,
                 "dual-return packets: both, last (even blocks) or strongest (odd blocks)")
      .one_of({"both", "last", "strongest"});
  cli.add_flag("--keep-identical-returns", o.keep_identical_returns,
               "dual return: keep the second block's point where it repeats the first");
  cli.add_option("--interpolation", o.interpolation,
                 "azimuth between blocks: firing-time (the manuals' tables) or nebula (as nebula's "
                 "reference clouds)")
      .one_of({"firing-time", "nebula"});
  cli.add_option("--cut-by", o.cut_by,
                 "point: each point by its own azimuth; packet: whole packets as nebula cuts")
      .one_of({"point", "packet"});
  cli.add_flag("--partial-frames", o.partial_frames,
               "also publish revolutions that did not start at the cut azimuth (start, gaps, end)");
  cli.add_option("--min-rpm", o.min_rpm, "lowest motor speed the stream is sized for, rpm")
      .in_range(300U, 1200U);
  add_lidar_writer_options(cli, o);
}

std::optional<velodyne::Model> velodyne_model(const VelodyneStreamOptions& o) {
  if (o.model == "auto") return std::nullopt;
  return velodyne::parse_model(o.model);
}

Expected<velodyne::LidarStreamConfig> velodyne_stream_config(const VelodyneStreamOptions& o) {
  velodyne::LidarStreamConfig config;
  config.stream = o.stream;
  config.calibration = o.calibration;
  if (const auto model = velodyne_model(o)) config.assembler.model = *model;
  config.assembler.cut_azimuth_deg = o.cut_azimuth;
  config.assembler.min_range_m = o.min_range;
  config.assembler.max_range_m = o.max_range;
  config.assembler.returns = o.returns == "last"        ? velodyne::ReturnFilter::last
                             : o.returns == "strongest" ? velodyne::ReturnFilter::strongest
                                                        : velodyne::ReturnFilter::both;
  config.assembler.drop_identical_returns = !o.keep_identical_returns;
  config.assembler.interpolation = o.interpolation == "nebula" ? velodyne::AzimuthInterpolation::nebula
                                                               : velodyne::AzimuthInterpolation::firing_time;
  config.assembler.cut_by = o.cut_by == "packet" ? velodyne::CutBy::packet : velodyne::CutBy::point_azimuth;
  config.assembler.emit_partial_frames = o.partial_frames;
  config.min_rpm = o.min_rpm;
  if (auto applied = apply_lidar_writer_options(config, o); !applied) return applied.error();
  return config;
}

}  // namespace sim::apps
