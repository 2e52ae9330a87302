// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/hesai_options.hpp"

namespace sim::apps {
namespace {

std::string model_problem(const std::string& name) {
  if (name == "auto" || hesai::parse_model(name)) return {};
  return "unknown model '" + name + "'; use one of " + std::string(hesai::model_names()) +
         " or auto";
}

}  // namespace

void add_hesai_stream_options(CommandLine& cli, HesaiStreamOptions& o) {
  cli.add_stream("--stream", o.stream, "SIM stream to publish");
  cli.add_option("--model", o.model,
                 "sensor model (" + std::string(hesai::model_names()) +
                     "), or auto to detect it from the first packet")
      .type_name("MODEL")
      .check(model_problem);
  cli.add_option("--calibration", o.calibration, "the unit's angle-correction CSV (required)")
      .type_name("FILE");
  cli.add_option("--firetimes", o.firetimes,
                 "optional firing-time CSV (replaces the built-in firing times)")
      .type_name("FILE");
  cli.add_option("--cut-azimuth", o.cut_azimuth,
                 "azimuth in degrees where one revolution ends and the next begins")
      .in_range(0.0, 359.99);
  cli.add_option_function<float>("--min-range", [&o](float v) { o.min_range = v; },
                                 "drop points closer than this, metres [the model's limit]")
      .type_name("FLOAT")
      .non_negative();
  cli.add_option_function<float>("--max-range", [&o](float v) { o.max_range = v; },
                                 "drop points farther than this, metres [the model's limit]")
      .type_name("FLOAT")
      .positive();
  cli.add_flag("--keep-zero-distance", o.keep_zero_distance,
               "keep firings without a return (as points at the origin)");
  cli.add_flag("--keep-identical-returns", o.keep_identical_returns,
               "multi-return: keep returns identical to the group's last one");
  cli.add_option("--dual-return-threshold", o.dual_return_threshold,
                 "multi-return: drop a non-last return this close to another, metres; 0 keeps all")
      .non_negative();
  cli.add_flag("--partial-frames", o.partial_frames,
               "also publish revolutions that did not start at the cut azimuth (start, gaps, end)");
  cli.add_flag("--firetime-azimuth-compensation", o.firetime_azimuth_compensation,
               "with --firetimes: correct each point's azimuth for its firing time (Hesai SDK 2 "
               "style)");
  cli.add_option("--returns", o.returns,
                 "returns per firing the stream is sized for (raised to what the packets announce)")
      .in_range(1U, 3U);
  cli.add_option("--min-rpm", o.min_rpm, "lowest motor speed the stream is sized for, rpm")
      .in_range(300U, 1200U);
  add_lidar_writer_options(cli, o);
}

std::optional<hesai::Model> hesai_model(const HesaiStreamOptions& o) {
  if (o.model == "auto") return std::nullopt;
  return hesai::parse_model(o.model);
}

Expected<hesai::LidarStreamConfig> hesai_stream_config(const HesaiStreamOptions& o) {
  hesai::LidarStreamConfig config;
  config.stream = o.stream;
  config.calibration = o.calibration;
  if (!o.firetimes.empty()) config.firetimes = o.firetimes;
  if (const auto model = hesai_model(o)) config.assembler.model = *model;
  config.assembler.cut_azimuth_deg = o.cut_azimuth;
  config.assembler.min_range_m = o.min_range;
  config.assembler.max_range_m = o.max_range;
  config.assembler.drop_zero_distance = !o.keep_zero_distance;
  config.assembler.drop_identical_returns = !o.keep_identical_returns;
  config.assembler.multi_return_distance_threshold_m = o.dual_return_threshold;
  config.assembler.emit_partial_frames = o.partial_frames;
  config.assembler.firetime_azimuth_compensation = o.firetime_azimuth_compensation;
  config.returns = o.returns;
  config.min_rpm = o.min_rpm;
  if (auto applied = apply_lidar_writer_options(config, o); !applied) return applied.error();
  return config;
}

}  // namespace sim::apps
