// SPDX-License-Identifier: Apache-2.0
// sim_rm: removes SIM streams. A stream with a live writer is kept unless --force.
#include <cstdio>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/reader.hpp"

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_rm",
      "Remove SIM streams (their shared-memory regions). A stream whose writer is alive is "
      "refused unless --force; --dead removes every stream whose writer is gone.");
  std::vector<std::string> names;
  bool force = false;
  bool dead = false;
  cli.add_streams("names", names, "stream names, like /lidar_top");
  cli.add_flag("--force", force,
               "remove even when the writer is alive (its readers keep their copy of the region "
               "until they close it)");
  cli.add_flag("--dead", dead,
               "remove the named streams, or every stream if none is named, whose writer is "
               "gone");
  if (auto code = cli.parse(argc, argv)) return *code;
  if (names.empty() && !dead) return cli.usage_error("name a stream to remove, or pass --dead");
  const auto& stop = sim::apps::StopSignal::install();

  int failures = 0;
  const auto remove = [&](const std::string& name, bool forced) {
    if (auto removed = sim::destroy(name, forced); !removed) {
      cli.fail(std::string_view(removed.error().message));
      ++failures;
    } else {
      std::printf("removed %s\n", name.c_str());
    }
  };
  if (dead) {
    for (const auto& name : names.empty() ? sim::list_streams() : names) {
      if (stop.requested()) break;
      auto status = sim::inspect(name);
      // A region that fails validation has no writer that could be using it either.
      if (status && status->writer_alive) {
        std::printf("kept %s: its writer is alive\n", name.c_str());
        continue;
      }
      remove(name, false);
    }
  } else {
    for (const auto& name : names) {
      if (stop.requested()) break;
      remove(name, force);
    }
  }
  return failures == 0 ? sim::apps::kExitOk : sim::apps::kExitFailure;
}
