// SPDX-License-Identifier: Apache-2.0
// What every SIM tool does the same way: parse options with CLI11 and exit with codes scripts can
// trust: 0 done, 1 failed at run time, 2 the command line was wrong (--help exits 0).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>

#include "sim/os.hpp"

namespace sim::tools {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// Parses the command line; returns an exit code when the tool should stop now.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help or the error
    return code == 0 ? kExitOk : kExitUsage;
  }
  return std::nullopt;
}

// Where the tool's main thread runs: --cpu and --rt-priority, shared by every tool and driver.
using Placement = sim::ThreadPlacement;

inline void add_placement_options(CLI::App& app, Placement& placement) {
  app.add_option("--cpu", placement.cpu, "pin the main thread to this CPU");
  app.add_option("--rt-priority", placement.rt_priority,
                 "run under SCHED_FIFO at this priority (1-99; needs root or CAP_SYS_NICE)");
}

// Applies the placement; returns an exit code when it cannot be applied: usage for a CPU or
// priority that cannot be had, failure when the process lacks the right to use them.
inline std::optional<int> apply_placement(const Placement& placement, const char* tool) {
  const auto placed = sim::apply_thread_placement(placement);
  if (placed) return std::nullopt;
  std::fprintf(stderr, "%s: %s\n", tool, placed.error().message.c_str());
  return placed.error().code == sim::ErrorCode::permission_denied ? kExitFailure : kExitUsage;
}

}  // namespace sim::tools
