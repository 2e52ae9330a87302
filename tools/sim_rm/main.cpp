// SPDX-License-Identifier: Apache-2.0
// sim_rm: removes SIM streams. A stream with a live writer is kept unless --force.
#include <cstdio>
#include <string>
#include <vector>

#include "sim/reader.hpp"
#include "sim_tools/cli.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Remove SIM streams (their shared-memory regions). A stream whose writer is alive "
               "is refused unless --force; --dead removes every stream whose writer is gone."};
  std::vector<std::string> names;
  bool force = false;
  bool dead = false;
  app.add_option("names", names, "stream names, like /lidar_top");
  app.add_flag("--force", force, "remove even when the writer is alive (its readers keep their copy "
                                 "of the region until they close it)");
  app.add_flag("--dead", dead, "remove the named streams, or every stream if none is named, whose "
                              "writer is gone");
  if (auto code = sim::tools::parse(app, argc, argv)) return *code;
  if (names.empty() && !dead) {
    std::fprintf(stderr, "sim_rm: name a stream to remove, or pass --dead; see --help\n");
    return 2;
  }

  int failures = 0;
  if (dead) {
    for (const auto& name : names.empty() ? sim::list_streams() : names) {
      auto status = sim::inspect(name);
      // A region that fails validation has no writer that could be using it either.
      if (status && status->writer_alive) {
        std::printf("kept %s: its writer is alive\n", name.c_str());
        continue;
      }
      if (auto removed = sim::destroy(name); !removed) {
        std::fprintf(stderr, "sim_rm: %s\n", removed.error().message.c_str());
        ++failures;
      } else {
        std::printf("removed %s\n", name.c_str());
      }
    }
  }
  for (const auto& name : dead ? std::vector<std::string>{} : names) {
    if (auto removed = sim::destroy(name, force); !removed) {
      std::fprintf(stderr, "sim_rm: %s\n", removed.error().message.c_str());
      ++failures;
    } else {
      std::printf("removed %s\n", name.c_str());
    }
  }
  return failures == 0 ? 0 : 1;
}
