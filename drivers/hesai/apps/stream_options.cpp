// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/stream_options.hpp"

#include "sim/os.hpp"

namespace sim::hesai {

void add_stream_options(CLI::App& app, StreamOptions& o) {
  app.add_option_function<std::string>(
         "--stream", [&o](const std::string& v) { o.config.stream = v; },
         "SIM stream to publish, e.g. /lidar_top")
      ->type_name("NAME");
  app.add_option_function<std::string>(
         "--model",
         [&o](const std::string& v) {
           if (v == "auto") {
             o.model.reset();
             return;
           }
           const auto model = parse_model(v);
           if (!model) {
             throw CLI::ValidationError("--model", "unknown model '" + v + "'; use one of " +
                                                       std::string(model_names()) + " or auto");
           }
           o.model = *model;
         },
         "sensor model (" + std::string(model_names()) + "), or auto to detect it from the "
         "first packet [auto]")
      ->type_name("MODEL");
  app.add_option_function<std::string>(
         "--calibration", [&o](const std::string& v) { o.config.calibration = v; },
         "the unit's angle-correction CSV (required)")
      ->type_name("FILE");
  app.add_option_function<std::string>(
         "--firetimes", [&o](const std::string& v) { o.config.firetimes = v; },
         "optional firing-time CSV (replaces the built-in firing times)")
      ->type_name("FILE");
  app.add_option_function<double>(
         "--cut-azimuth", [&o](double v) { o.config.assembler.cut_azimuth_deg = v; },
         "azimuth in degrees where one revolution ends and the next begins [0]")
      ->check(CLI::Range(0.0, 359.99));
  app.add_option_function<float>(
         "--min-range", [&o](float v) { o.config.assembler.min_range_m = v; },
         "drop points closer than this, metres [model's limit]")
      ->check(CLI::NonNegativeNumber);
  app.add_option_function<float>(
         "--max-range", [&o](float v) { o.config.assembler.max_range_m = v; },
         "drop points farther than this, metres [model's limit]")
      ->check(CLI::PositiveNumber);
  app.add_flag_callback(
      "--keep-zero-distance", [&o] { o.config.assembler.drop_zero_distance = false; },
      "keep firings without a return (as points at the origin)");
  app.add_flag_callback(
      "--keep-identical-returns", [&o] { o.config.assembler.drop_identical_returns = false; },
      "multi-return: keep returns identical to the group's last one");
  app.add_option_function<float>(
         "--dual-return-threshold",
         [&o](float v) { o.config.assembler.multi_return_distance_threshold_m = v; },
         "multi-return: drop a non-last return this close to another, metres; 0 keeps all [0.1]")
      ->check(CLI::NonNegativeNumber);
  app.add_flag_callback(
      "--partial-frames", [&o] { o.config.assembler.emit_partial_frames = true; },
      "also publish revolutions that did not start at the cut azimuth (start, gaps, end)");
  app.add_flag_callback(
      "--firetime-azimuth-compensation",
      [&o] { o.config.assembler.firetime_azimuth_compensation = true; },
      "with --firetimes: correct each point's azimuth for its firing time (Hesai SDK 2 style)");
  app.add_option_function<unsigned>(
         "--returns", [&o](unsigned v) { o.config.returns = v; },
         "returns per firing the stream is sized for [2; raised to what the packets announce]")
      ->check(CLI::Range(1u, 3u));
  app.add_option_function<unsigned>(
         "--min-rpm", [&o](unsigned v) { o.config.min_rpm = v; },
         "lowest motor speed the stream is sized for, rpm [600]")
      ->check(CLI::Range(300u, 1200u));
  app.add_flag_callback("--checksum", [&o] { o.config.checksum = true; },
                        "add an XXH3 checksum to every frame, verified by readers");
  app.add_flag_callback("--lock-memory", [&o] { o.config.lock_memory = true; },
                        "mlock the stream's shared memory");
  app.add_option_function<int>("--cpu", [&o](int v) { o.cpu = v; },
                               "pin the receiving thread to this CPU")
      ->check(CLI::NonNegativeNumber);
  app.add_option_function<int>("--rt-priority", [&o](int v) { o.rt_priority = v; },
                               "run under SCHED_FIFO at this priority (1-99; needs CAP_SYS_NICE)")
      ->check(CLI::Range(1, 99));
}

Expected<void> apply_thread_placement(const StreamOptions& options) {
  ThreadPlacement placement;
  if (options.cpu >= 0) placement.cpu = options.cpu;
  if (options.rt_priority > 0) placement.rt_priority = options.rt_priority;
  return sim::apply_thread_placement(placement);
}

}  // namespace sim::hesai
