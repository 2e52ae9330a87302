// SPDX-License-Identifier: Apache-2.0
// sim_echo: prints the frames of a stream (one readable line each, or JSON with --json), or with
// --stats their rate, interval spread, latency, delay, bandwidth and skips.
#include <cstdio>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "frame_stats.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/apps/clock_text.hpp"
#include "sim/apps/sensor_text.hpp"
#include "sim/reader.hpp"

namespace {

struct Options {
  std::string stream;
  std::uint64_t count = 0;
  bool json = false;
  bool stats = false;
  double interval_s = 1.0;
  double timeout_s = 0;
  double duration_s = 0;
  bool wait_for_stream = false;
  bool poll = false;
  sim::ThreadPlacement placement;
  sim::ReaderOptions reader;
};

void print_frame(const Options& o, const sim::FrameInfo& info, std::int64_t read_ns,
                 std::int64_t read_realtime_ns, std::uint64_t skipped) {
  const double latency_us = static_cast<double>(read_ns - info.publish_ns) / 1e3;
  const double delay_us =
      info.stamp_ns != 0 ? static_cast<double>(read_realtime_ns - info.stamp_ns) / 1e3 : 0.0;
  if (o.json) {
    std::printf(
        "{\"seq\":%llu,\"stamp_ns\":%lld,\"receive_ns\":%lld,\"publish_ns\":%lld,"
        "\"size\":%llu,\"latency_us\":%.1f,\"delay_us\":%.1f,\"skipped\":%llu,\"layout\":\"%s\","
        "\"sensor_generation\":%llu,\"clock_generation\":%llu,\"stamp_clock\":\"%s\"}\n",
        static_cast<unsigned long long>(info.seq), static_cast<long long>(info.stamp_ns),
        static_cast<long long>(info.receive_ns), static_cast<long long>(info.publish_ns),
        static_cast<unsigned long long>(info.size), latency_us, delay_us,
        static_cast<unsigned long long>(skipped), info.layout.describe().c_str(),
        static_cast<unsigned long long>(info.sensor_generation),
        static_cast<unsigned long long>(info.clock_generation), sim::to_string(info.stamp_clock));
  } else {
    std::printf("seq %llu  size %llu B  latency %.1f us  delay %.1f us  skipped %llu  %s\n",
                static_cast<unsigned long long>(info.seq),
                static_cast<unsigned long long>(info.size), latency_us, delay_us,
                static_cast<unsigned long long>(skipped), info.layout.describe().c_str());
  }
  std::fflush(stdout);
}

// The stream's sensor description, printed before the first frame and again whenever the writer
// changes it (a recalibration, a remount): FrameInfo::sensor_generation says when. A stream
// without one gets no such line.
void print_sensor(const Options& o, const sim::Reader& reader, std::uint64_t generation) {
  std::string text;
  std::string json = "null";
  if (generation == 0) {
    text = "none";
  } else if (auto info = reader.sensor_info(); !info) {
    text = "damaged: " + info.error().message;
    json = "{\"problem\":" + sim::apps::json_string(info.error().message) + "}";
  } else if (!info->has_value()) {
    text = "none";
  } else {
    text = sim::apps::describe_sensor(**info);
    json = sim::apps::sensor_json(**info);
  }
  if (o.json) {
    std::printf("{\"sensor_generation\":%llu,\"sensor\":%s}\n",
                static_cast<unsigned long long>(generation), json.c_str());
  } else {
    std::printf("sensor %s\n", text.c_str());
  }
}

// The stream's clock in one line with its verdict, printed before the first frame and again
// whenever the writer's clock record changes (FrameInfo::clock_generation), so a reader sees at
// once whether the stamps below can be trusted. A stream without one gets no such line.
void print_clock(const Options& o, const sim::Reader& reader) {
  sim::apps::StreamClock stream;
  if (auto clock = reader.clock()) {
    stream.clock = *clock;
  } else {
    stream.problem = clock.error().message;
  }
  if (o.json) {
    std::printf("{\"clock\":%s}\n", sim::apps::clock_json(stream).c_str());
  } else {
    std::printf("clock %s\n", sim::apps::describe_clock(stream).c_str());
  }
}

void print_stats(const Options& o, const char* label, const sim::echo::FrameStats& stats) {
  if (o.json) {
    std::printf("{\"%s\":\"%s\",%s}\n", label, o.stream.c_str(), stats.json_fields().c_str());
  } else {
    std::printf("%s %s  %s\n", label, o.stream.c_str(), stats.describe().c_str());
  }
  std::fflush(stdout);
}

void add_options(sim::apps::CommandLine& cli, Options& o) {
  cli.add_stream("stream", o.stream, "stream name, like /lidar_top").required();
  cli.add_option("--count,-n", o.count, "exit after this many frames (0: until stopped)");
  cli.add_flag("--json", o.json, "JSON lines for scripts instead of readable lines");
  cli.add_flag("--stats", o.stats, "print statistics every --interval instead of frames");
  cli.add_option("--interval", o.interval_s, "seconds between --stats lines")
      .positive();
  cli.add_option("--timeout", o.timeout_s,
                 "fail (exit 1) when no frame arrives for this many seconds (0: never)")
      .non_negative();
  cli.add_option("--duration", o.duration_s, "stop after this many seconds (0: never)")
      .non_negative();
  cli.add_flag("--wait-for-stream", o.wait_for_stream, "wait until the stream exists");
  cli.add_flag("--poll", o.poll, "busy-poll instead of sleeping until each frame (uses a core)");
  cli.add_placement(o.placement);
  cli.add_trust(o.reader.trust);
}

// --duration, counted from the start of the program.
struct RunTime {
  std::int64_t start_ns = sim::monotonic_ns();
  bool past(double seconds) const {
    return seconds > 0 && static_cast<double>(sim::monotonic_ns() - start_ns) / 1e9 >= seconds;
  }
};

// Opens the stream; with --wait-for-stream it tries again until the stream exists, a stop or the
// end of --duration.
sim::Expected<sim::Reader> open_reader(const Options& o, const sim::apps::StopSignal& stop,
                                       const RunTime& run) {
  auto reader = sim::Reader::open(o.stream, o.reader);
  while (!reader && o.wait_for_stream && reader.error().code == sim::ErrorCode::not_found &&
         !run.past(o.duration_s) && stop.sleep_for(std::chrono::milliseconds(100))) {
    reader = sim::Reader::open(o.stream, o.reader);
  }
  return reader;
}

// What the loop keeps from frame to frame.
struct Echo {
  sim::echo::FrameStats window;
  sim::echo::FrameStats total;
  std::int64_t window_start = sim::monotonic_ns();
  std::int64_t last_frame_at = window_start;
  // Of the last description printed: a stream without one prints no sensor line at all.
  std::uint64_t sensor_generation = 0;
  // Of the last clock line printed: a stream without a clock record prints no clock line at all.
  std::uint64_t clock_generation = 0;
};

// Counts a new frame and prints it (with --stats: adds it to the window). True when --count
// frames were taken.
bool take_frame(const Options& o, const sim::Reader& reader, const sim::FrameInfo& info,
                std::int64_t now, Echo& e) {
  e.last_frame_at = now;
  const sim::echo::Frame frame{info.seq, info.size, info.publish_ns, now, info.stamp_ns,
                               sim::realtime_ns()};
  e.total.add(frame);
  if (o.stats) {
    e.window.add(frame);
  } else {
    if (e.sensor_generation != info.sensor_generation) {
      print_sensor(o, reader, info.sensor_generation);
      e.sensor_generation = info.sensor_generation;
    }
    if (e.clock_generation != info.clock_generation) {
      print_clock(o, reader);
      e.clock_generation = info.clock_generation;
    }
    print_frame(o, info, frame.read_ns, frame.read_realtime_ns, e.total.skipped());
  }
  return o.count != 0 && e.total.frames() >= o.count;
}

// The sentence when --timeout passed without a frame.
std::optional<std::string> timeout_problem(const Options& o, sim::Reader& reader,
                                           std::int64_t now, const Echo& e) {
  if (o.timeout_s <= 0 || static_cast<double>(now - e.last_frame_at) / 1e9 <= o.timeout_s) {
    return std::nullopt;
  }
  char message[256];
  std::snprintf(message, sizeof message, "no frame on %s for %.1f s (its writer is %s)",
                o.stream.c_str(), o.timeout_s, reader.writer_alive() ? "alive" : "gone");
  return message;
}

// Reads and prints frames until a stop, --duration, --count, --timeout or a damaged stream.
int echo_frames(const sim::apps::CommandLine& cli, const Options& o, sim::Reader& reader,
                const sim::apps::StopSignal& stop, const RunTime& run) {
  // Frames published before this moment are the past: not counted, not printed.
  const std::int64_t opened_ns = sim::monotonic_ns();
  std::vector<std::byte> buffer(reader.capacity());
  Echo e;
  int exit_code = sim::apps::kExitOk;
  const auto slice = std::chrono::milliseconds(100);
  while (!stop.requested() && !run.past(o.duration_s)) {
    sim::FrameInfo info;
    const sim::ReadStatus status =
        o.poll ? reader.read(buffer, info) : reader.read_next(buffer, info, slice);
    if (status == sim::ReadStatus::buffer_too_small) {
      buffer.resize(reader.capacity());  // the writer recreated the stream with a larger layout
      continue;
    }
    const std::int64_t now = sim::monotonic_ns();
    if (status == sim::ReadStatus::new_frame && info.publish_ns >= opened_ns) {
      if (take_frame(o, reader, info, now, e)) break;
    } else if (status == sim::ReadStatus::region_invalid) {
      cli.fail("stream " + o.stream + " failed validation; restart its writer");
      exit_code = sim::apps::kExitFailure;
      break;
    } else if (o.poll && status != sim::ReadStatus::new_frame) {
      std::this_thread::yield();
    }
    if (auto problem = timeout_problem(o, reader, now, e)) {
      cli.fail(*problem);
      exit_code = sim::apps::kExitFailure;
      break;
    }
    if (o.stats && static_cast<double>(now - e.window_start) / 1e9 >= o.interval_s) {
      print_stats(o, "stream", e.window);
      e.window = sim::echo::FrameStats{};
      e.window_start = now;
    }
  }
  if (o.stats) print_stats(o, "summary", e.total);
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  sim::apps::CommandLine cli(
      "sim_echo",
      "Print the frames of a SIM stream, one line each (seq, size, latency = publish to read, "
      "delay = sensor stamp to read, layout), or with --stats its rate (with the spread of the "
      "intervals), latency, delay, bandwidth and skipped frames. Frames published before "
      "sim_echo started are not counted.");
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (auto code = cli.apply_placement(o.placement)) return *code;

  const auto& stop = sim::apps::StopSignal::install();
  const RunTime run;
  auto reader = open_reader(o, stop, run);
  if (!reader) {
    if (stop.requested() || run.past(o.duration_s)) return sim::apps::kExitOk;
    return cli.fail(std::string_view(reader.error().message));
  }
  return echo_frames(cli, o, *reader, stop, run);
}
