// SPDX-License-Identifier: Apache-2.0
// sim_ls: every SIM stream on this machine, with its layout, rate, age and writer.
#include <cstdio>
#include <string>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim_tools/cli.hpp"

namespace {

std::string age_text(std::int64_t now, std::int64_t then) {
  if (then == 0) return "never";
  const double seconds = static_cast<double>(now - then) / 1e9;
  char text[32];
  std::snprintf(text, sizeof(text), seconds < 1 ? "%.0f ms" : "%.1f s",
                seconds < 1 ? seconds * 1e3 : seconds);
  return text;
}

std::string json_escape(const std::string& in) {
  std::string out;
  for (const char c : in) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"List every SIM stream on this machine: layout, capacity, frames, rate, age of the "
               "newest frame, writer and checksum."};
  bool json = false;
  app.add_flag("--json", json, "one JSON object per stream instead of a table");
  if (auto code = sim::tools::parse(app, argc, argv)) return *code;

  const auto names = sim::list_streams();
  if (!json) {
    std::printf("%-24s %-36s %12s %10s %8s %9s %-22s %s\n", "STREAM", "LAYOUT", "CAPACITY",
                "FRAMES", "RATE", "AGE", "WRITER", "CHECKSUM");
  }
  int problems = 0;
  for (const auto& name : names) {
    auto status = sim::inspect(name);
    if (!status) {
      ++problems;
      if (json) {
        std::printf("{\"name\":\"%s\",\"error\":\"%s\"}\n", name.c_str(),
                    json_escape(status.error().message).c_str());
      } else {
        std::printf("%-24s %s\n", name.c_str(), status.error().message.c_str());
      }
      continue;
    }
    const sim::StreamStatus& s = *status;
    const std::int64_t now = sim::monotonic_ns();
    // Rate over the writer's lifetime would mislead after a pause; max interval is what the
    // header keeps, so show the average since the writer started only when it is alive.
    const double uptime_s =
        static_cast<double>(sim::realtime_ns() - s.writer_start_realtime_ns) / 1e9;
    const double rate = (s.writer_alive && uptime_s > 0)
                            ? static_cast<double>(s.frames_published) / uptime_s
                            : 0.0;
    const std::string writer = s.writer_alive ? "alive pid " + std::to_string(s.writer_pid) +
                                                    " " + s.writer_command
                                              : "gone";
    if (json) {
      std::printf(
          "{\"name\":\"%s\",\"layout\":\"%s\",\"capacity\":%llu,\"frames\":%llu,\"latest_seq\":%llu,"
          "\"rate_hz\":%.2f,\"age_ns\":%lld,\"max_interval_ns\":%lld,\"writer_alive\":%s,"
          "\"writer_pid\":%d,\"writer\":\"%s\",\"checksum\":%s,\"sleeping_readers\":%u}\n",
          s.name.c_str(), s.layout.describe().c_str(),
          static_cast<unsigned long long>(s.capacity),
          static_cast<unsigned long long>(s.frames_published),
          static_cast<unsigned long long>(s.latest_seq), rate,
          static_cast<long long>(s.latest_publish_ns == 0 ? -1 : now - s.latest_publish_ns),
          static_cast<long long>(s.max_publish_interval_ns), s.writer_alive ? "true" : "false",
          s.writer_pid, json_escape(s.writer_command).c_str(), s.checksum ? "true" : "false",
          s.sleeping_readers);
    } else {
      std::printf("%-24s %-36s %12llu %10llu %6.1fHz %9s %-22s %s\n", s.name.c_str(),
                  s.layout.describe().c_str(), static_cast<unsigned long long>(s.capacity),
                  static_cast<unsigned long long>(s.frames_published), rate,
                  age_text(now, s.latest_publish_ns).c_str(), writer.c_str(),
                  s.checksum ? "xxh3" : "off");
    }
  }
  return problems == 0 ? 0 : 1;
}
