// SPDX-License-Identifier: Apache-2.0
// What every SIM tool does the same way: parse options with CLI11 and exit with codes scripts can
// trust: 0 done, 1 failed at run time, 2 the command line was wrong (--help exits 0).
#pragma once

#include <CLI/CLI.hpp>
#include <optional>

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

}  // namespace sim::tools
