// SPDX-License-Identifier: Apache-2.0
// sim_ls: every SIM stream on this machine, with its layout, rate, age and writer; --watch
// keeps a live view of them all (rate, bandwidth, age, latency, skips, sleeping readers, writer),
// refreshed in place; --clocks puts the host's clock and every stream's side by side and says which
// streams can be paired by stamp.
#include <cstdio>
#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clocks.hpp"
#include "sim/apps/clock_text.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/host_clock_options.hpp"
#include "sim/apps/sensor_text.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/timing/host_clock.hpp"
#include "stream_watch.hpp"

namespace {

struct Options {
  bool json = false;
  bool watch = false;
  bool clocks = false;
  double tolerance_ms = 10.0;  // --clocks: the largest stamp difference of a pair
  sim::timing::HostClockOptions host_clock;  // --ptp4l-socket
  double interval_s = 1.0;
  double window_s = 0.5;
  std::vector<std::string> streams;  // only these; empty: every stream on the machine
};

std::string json_escape(const std::string& in) {
  std::string out;
  for (const char c : in) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", c);
      out += code;
    } else {
      out += c;
    }
  }
  return out;
}

std::string age_text(std::int64_t now, std::int64_t then) {
  if (then == 0) return "never";
  const double seconds = static_cast<double>(now - then) / 1e9;
  char text[32];
  std::snprintf(text, sizeof text, seconds < 1 ? "%.0f ms" : "%.1f s",
                seconds < 1 ? seconds * 1e3 : seconds);
  return text;
}

// One stream at one refresh.
struct Row {
  std::string name;
  std::optional<sim::StreamStatus> status;
  std::string error;
  double rate_hz = 0;                     // frames published per second over the recent window
  std::optional<sim::ls::WatchSample> seen;  // --watch: what the view's reader counted
  double seen_span_s = 0;
};

// Rates are measured over a recent window on CLOCK_MONOTONIC: the frames the same writer
// published between two looks, so a restart or a clock step cannot make them up.
class RateMeter {
 public:
  double update(const sim::StreamStatus& s, std::int64_t now) {
    Sample& last = samples_[s.name];
    double rate = 0;
    if (last.at != 0 && last.pid == s.writer_pid && last.start == s.writer_start_realtime_ns &&
        s.frames_published >= last.frames && now > last.at) {
      rate = static_cast<double>(s.frames_published - last.frames) /
             (static_cast<double>(now - last.at) / 1e9);
    }
    last = {now, s.writer_pid, s.writer_start_realtime_ns, s.frames_published};
    return rate;
  }

 private:
  struct Sample {
    std::int64_t at = 0;
    std::int32_t pid = 0;
    std::int64_t start = 0;
    std::uint64_t frames = 0;
  };
  std::map<std::string, Sample> samples_;
};

void print_json(const Row& row, std::int64_t now) {
  if (!row.status) {
    std::printf("{\"name\":\"%s\",\"error\":\"%s\"}\n", json_escape(row.name).c_str(),
                json_escape(row.error).c_str());
    return;
  }
  const sim::StreamStatus& s = *row.status;
  std::string watched;
  if (row.seen) {
    const auto& w = *row.seen;
    char text[256];
    std::snprintf(text, sizeof text,
                  ",\"bandwidth_bytes_per_s\":%.0f,\"latency_us\":{\"mean\":%.1f,\"max\":%.1f},"
                  "\"skipped\":%llu",
                  row.seen_span_s > 0 ? static_cast<double>(w.bytes) / row.seen_span_s : 0.0,
                  w.frames ? w.latency_us_sum / static_cast<double>(w.frames) : 0.0,
                  w.latency_us_max, static_cast<unsigned long long>(w.skipped));
    watched = text;
  }
  std::printf(
      "{\"name\":\"%s\",\"layout\":\"%s\",\"capacity\":%llu,\"frames\":%llu,\"latest_seq\":%llu,"
      "\"rate_hz\":%.2f,\"age_ns\":%lld,\"max_interval_ns\":%lld,\"writer_alive\":%s,"
      "\"writer_pid\":%d,\"writer\":\"%s\",\"checksum\":%s,\"sleeping_readers\":%u%s,"
      "\"sensor\":%s%s,\"clock\":%s}\n",
      json_escape(s.name).c_str(), json_escape(s.layout.describe()).c_str(),
      static_cast<unsigned long long>(s.capacity),
      static_cast<unsigned long long>(s.frames_published),
      static_cast<unsigned long long>(s.latest_seq), row.rate_hz,
      static_cast<long long>(s.latest_publish_ns == 0 ? -1 : now - s.latest_publish_ns),
      static_cast<long long>(s.max_publish_interval_ns), s.writer_alive ? "true" : "false",
      s.writer_pid, json_escape(s.writer_command).c_str(), s.checksum ? "true" : "false",
      s.sleeping_readers, watched.c_str(),
      s.sensor ? sim::apps::sensor_json(*s.sensor).c_str() : "null",
      s.sensor_problem.empty()
          ? ""
          : (",\"sensor_problem\":" + sim::apps::json_string(s.sensor_problem)).c_str(),
      sim::apps::clock_json({s.clock, s.clock_problem}).c_str());
}

std::string writer_text(const sim::StreamStatus& s) {
  return s.writer_alive ? "pid " + std::to_string(s.writer_pid) + " " + s.writer_command
                        : "gone (was " + s.writer_command + ")";
}

void print_table(const std::vector<Row>& rows, std::int64_t now, bool watch) {
  std::size_t width = 6;
  for (const auto& row : rows) width = std::max(width, row.name.size());
  const int w = static_cast<int>(width);
  if (watch) {
    std::printf("%-*s %9s %11s %9s %10s %7s %8s  %-28s %s\n", w, "STREAM", "RATE", "BANDWIDTH",
                "AGE", "LATENCY", "SKIPPED", "SLEEPING", "WRITER", "LAYOUT");
  } else {
    std::printf("%-*s %-36s %12s %10s %9s %9s %8s  %-28s %s\n", w, "STREAM", "LAYOUT",
                "CAPACITY", "FRAMES", "RATE", "AGE", "SLEEPING", "WRITER", "CHECKSUM");
  }
  for (const auto& row : rows) {
    if (!row.status) {
      std::printf("%-*s %s\n", w, row.name.c_str(), row.error.c_str());
      continue;
    }
    const sim::StreamStatus& s = *row.status;
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.1f Hz", row.rate_hz);
    if (watch) {
      const auto seen = row.seen.value_or(sim::ls::WatchSample{});
      char latency[32] = "-";
      if (seen.frames > 0) {
        std::snprintf(latency, sizeof latency, "%.0f us",
                      seen.latency_us_sum / static_cast<double>(seen.frames));
      }
      const double bandwidth =
          row.seen_span_s > 0 ? static_cast<double>(seen.bytes) / row.seen_span_s : 0.0;
      // The view's own reader is one of the sleepers: do not count it.
      const unsigned sleeping = s.sleeping_readers > 0 ? s.sleeping_readers - 1 : 0;
      std::printf("%-*s %9s %11s %9s %10s %7llu %8u  %-28s %s\n", w, s.name.c_str(), rate,
                  sim::apps::bandwidth(bandwidth).c_str(), age_text(now, s.latest_publish_ns).c_str(),
                  latency, static_cast<unsigned long long>(seen.skipped), sleeping,
                  writer_text(s).c_str(), s.layout.describe().c_str());
    } else {
      std::printf("%-*s %-36s %12llu %10llu %9s %9s %8u  %-28s %s\n", w, s.name.c_str(),
                  s.layout.describe().c_str(), static_cast<unsigned long long>(s.capacity),
                  static_cast<unsigned long long>(s.frames_published), rate,
                  age_text(now, s.latest_publish_ns).c_str(), s.sleeping_readers,
                  writer_text(s).c_str(), s.checksum ? "xxh3" : "off");
      // The sensor's description under its stream: frame, parent, mounting, calibration.
      if (s.sensor) {
        std::printf("%-*s   sensor: %s\n", w, "", sim::apps::describe_sensor(*s.sensor).c_str());
      } else if (!s.sensor_problem.empty()) {
        std::printf("%-*s   sensor: damaged: %s\n", w, "", s.sensor_problem.c_str());
      }
      std::printf("%-*s   clock: %s\n", w, "", sim::apps::describe_clock({s.clock, s.clock_problem}).c_str());
    }
  }
}

// The named streams, or every stream: then one that vanished between listing and looking (its
// writer removed it) is simply gone, not a problem; a named one that is missing is.
std::vector<Row> look(RateMeter& rates, const std::vector<std::string>& named) {
  std::vector<Row> rows;
  const std::int64_t now = sim::monotonic_ns();
  for (const auto& name : named.empty() ? sim::list_streams() : named) {
    Row row;
    row.name = name;
    auto status = sim::inspect(name);
    if (status) {
      row.rate_hz = rates.update(*status, now);
      row.status = std::move(*status);
    } else if (named.empty() && status.error().code == sim::ErrorCode::not_found) {
      continue;
    } else {
      row.error = status.error().message;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

// --clocks: the host's clock (asked of ptp4l itself), every stream's, and the pairs; exit 1 when
// any stream's clock is in error, so a launch script can refuse to start the stack.
int show_clocks(const Options& o, const std::vector<Row>& rows, std::int64_t now) {
  const sim::ClockStatus host = sim::timing::read_host_clock(o.host_clock);
  std::vector<sim::ls::ClockRow> clocks;
  for (const auto& row : rows) {
    if (row.status) clocks.push_back({row.name, row.status->clock, row.status->clock_problem});
  }
  const auto tolerance_ns = static_cast<std::int64_t>(o.tolerance_ms * 1e6);
  if (o.json) {
    sim::ls::print_host_json(host);
    for (const auto& row : rows) print_json(row, now);
    sim::ls::print_pairs_json(clocks, tolerance_ns);
  } else {
    sim::ls::print_clocks_table(host, clocks, tolerance_ns);
  }
  const bool unreadable = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return !r.status; });
  return sim::ls::any_clock_in_error(clocks) || unreadable ? sim::apps::kExitFailure : sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  sim::apps::CommandLine cli(
      "sim_ls",
      "List the SIM streams on this machine (every stream, or the ones named): layout, "
      "capacity, frames, rate (over a recent window), age of the newest frame, sleeping readers, "
      "writer, checksum and clock. --watch keeps a live view: rate, bandwidth, age, latency (publish to "
      "read), skipped frames, sleeping readers and writer of each stream, refreshed in place "
      "until stopped.");
  cli.add_flag("--json", o.json, "one JSON object per stream (per refresh with --watch)");
  const auto watch = cli.add_flag("--watch,-w", o.watch, "live view, refreshed every --interval until stopped");
  cli.add_flag("--clocks", o.clocks,
               "the host's clock and every stream's side by side, and which streams can be paired by "
               "stamp within --tolerance; exit 1 when any stream's clock is in error")
      .excludes(watch);
  cli.add_option("--tolerance", o.tolerance_ms, "--clocks: the largest stamp difference of a pair, ms")
      .in_range(0.0, 3.6e6);
  sim::apps::add_host_clock_options(cli, o.host_clock);
  cli.add_option("--interval", o.interval_s, "seconds between --watch refreshes")
      .in_range(0.05, 3600.0);
  cli.add_option("--window", o.window_s, "seconds over which a single listing measures rates")
      .in_range(0.0, 60.0);
  cli.add_streams("streams", o.streams, "only these streams (default: every stream)");
  if (auto code = cli.parse(argc, argv)) return *code;
  const auto& stop = sim::apps::StopSignal::install();

  RateMeter rates;
  if (!o.watch) {
    look(rates, o.streams);  // the first look of the rate window
    if (o.window_s > 0 && !stop.sleep_for_seconds(o.window_s)) return 0;
    const auto rows = look(rates, o.streams);
    const std::int64_t now = sim::monotonic_ns();
    if (o.clocks) return show_clocks(o, rows, now);
    int problems = 0;
    if (o.json) {
      for (const auto& row : rows) print_json(row, now);
    } else {
      print_table(rows, now, false);
    }
    for (const auto& row : rows) problems += row.status ? 0 : 1;
    return problems == 0 ? sim::apps::kExitOk : sim::apps::kExitFailure;
  }

  const bool terminal = ::isatty(STDOUT_FILENO) != 0 && !o.json;
  std::map<std::string, std::unique_ptr<sim::ls::StreamWatch>> watches;
  std::int64_t last = sim::monotonic_ns();
  look(rates, o.streams);
  while (stop.sleep_for_seconds(o.interval_s)) {
    auto rows = look(rates, o.streams);
    const std::int64_t now = sim::monotonic_ns();
    std::map<std::string, std::unique_ptr<sim::ls::StreamWatch>> kept;
    for (auto& row : rows) {
      auto found = watches.find(row.name);
      if (found != watches.end()) {
        row.seen = found->second->take();
        row.seen_span_s = static_cast<double>(now - last) / 1e9;
        kept.emplace(row.name, std::move(found->second));
      } else if (row.status) {
        // Looking only: the view accepts any owner's stream (sim::Trust::any_owner).
        sim::ReaderOptions look;
        look.trust = sim::Trust::any_owner();
        if (auto reader = sim::Reader::open(row.name, look)) {
          kept.emplace(row.name, std::make_unique<sim::ls::StreamWatch>(std::move(*reader)));
        }
      }
    }
    watches = std::move(kept);  // streams that went away: their watches end here
    last = now;
    if (terminal) std::printf("\033[H\033[J");  // redraw in place
    if (o.json) {
      for (const auto& row : rows) print_json(row, now);
    } else {
      print_table(rows, now, true);
      if (!terminal) std::printf("\n");
    }
    std::fflush(stdout);
  }
  return sim::apps::kExitOk;
}
