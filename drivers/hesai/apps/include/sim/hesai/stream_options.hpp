// SPDX-License-Identifier: Apache-2.0
// The decoder and stream options both Hesai tools take, declared once so sim_lidar_hesai and
// sim_replay_pcap spell and document them the same way.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "sim/hesai/lidar_stream.hpp"

namespace sim::hesai {

struct StreamOptions {
  LidarStreamConfig config;
  std::optional<Model> model;  // nullopt: detect it from the first packet
  int cpu = -1;                // pin the receiving thread; -1: no
  int rt_priority = 0;         // SCHED_FIFO priority; 0: normal scheduling
};

// Adds --stream --model --calibration --firetimes --cut-azimuth --min-range --max-range
// --keep-zero-distance --keep-identical-returns --dual-return-threshold --partial-frames
// --firetime-azimuth-compensation --returns --min-rpm --checksum --lock-memory --cpu
// --rt-priority. Callbacks write into `options` only for options given on the command line,
// so values loaded earlier (from a config file) stay unless overridden.
void add_stream_options(CLI::App& app, StreamOptions& options);

// Applies --cpu and --rt-priority to the calling thread; the error says what to do.
Expected<void> apply_thread_placement(const StreamOptions& options);

}  // namespace sim::hesai
