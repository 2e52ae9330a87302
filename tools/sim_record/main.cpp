// SPDX-License-Identifier: Apache-2.0
// sim_record: records SIM streams into an MCAP file (ROS 2 profile) that Foxglove, rosbag2 and
// the mcap CLI read, and that sim_play replays into SIM exactly as recorded.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "recorder.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/names.hpp"
#include "sim/reader.hpp"
#include "sim/ros2/message.hpp"

namespace {

using sim::record::RecorderProgress;
using sim::record::StreamCounters;

std::uint64_t total(const RecorderProgress& p, std::uint64_t StreamCounters::*field) {
  std::uint64_t sum = 0;
  for (const auto& s : p.streams) sum += s.*field;
  return sum;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

void print_result(const RecorderProgress& p, const std::string& output, const std::string& compression,
                  double seconds, const std::string& problem, bool json) {
  if (json) {
    std::printf("{\"file\":%s,\"bytes\":%llu,\"compression\":\"%s\",\"seconds\":%.3f,\"streams\":[",
                json_string(output).c_str(), static_cast<unsigned long long>(p.file_bytes),
                compression.c_str(), seconds);
    for (std::size_t i = 0; i < p.streams.size(); ++i) {
      const auto& s = p.streams[i];
      std::printf("%s{\"name\":%s,\"frames\":%llu,\"missed\":%llu,\"bytes\":%llu,\"unrecordable\":%llu}",
                  i ? "," : "", json_string(s.name).c_str(), static_cast<unsigned long long>(s.frames),
                  static_cast<unsigned long long>(s.missed), static_cast<unsigned long long>(s.bytes),
                  static_cast<unsigned long long>(s.unrecordable));
    }
    std::printf("],\"problem\":%s}\n", json_string(problem).c_str());
  } else {
    for (const auto& s : p.streams) {
      std::printf("%s: %llu frames, %.1f MB, missed %llu\n", s.name.c_str(),
                  static_cast<unsigned long long>(s.frames), static_cast<double>(s.bytes) / 1e6,
                  static_cast<unsigned long long>(s.missed));
    }
    std::printf("%s: %.1f MB in %.1f s (%s)\n", output.c_str(),
                static_cast<double>(p.file_bytes) / 1e6, seconds, compression.c_str());
  }
  std::fflush(stdout);
}

// What the command line asks for.
struct RecordOptions {
  std::string output;
  std::vector<std::string> streams;
  bool all = false;
  double duration_s = 0;
  std::string compression = "zstd";
  std::uint64_t chunk_kib = 4096;
  bool wait_for_streams = false;
  bool json = false;
  bool quiet = false;
  sim::Trust trust;
};

// The command line; returns an exit code when the program must end now (--help, usage error).
std::optional<int> parse_command_line(sim::apps::CommandLine& cli, int argc, char** argv, RecordOptions& o) {
  cli.add_option("-o,--output", o.output, "the MCAP file to write").required().type_name("FILE");
  cli.add_option("streams", o.streams, "streams to record, like /lidar_top /camera_front")
      .check([](const std::string& name) { return sim::stream_name_problem(name); });
  cli.add_flag("--all", o.all, "record every image and point stream that exists now");
  cli.add_option("--duration", o.duration_s, "stop after this many seconds [until Ctrl-C]")
      .positive()
      .type_name("S");
  cli.add_option("--compression", o.compression, "chunk compression: zstd, lz4 or none")
      .one_of({"zstd", "lz4", "none"});
  cli.add_option("--chunk-size", o.chunk_kib, "KiB of messages per chunk")
      .in_range(std::uint64_t{1}, std::uint64_t{1} << 20)
      .type_name("KIB");
  cli.add_flag("--wait-for-streams", o.wait_for_streams,
               "wait until every named stream exists, then record");
  cli.add_flag("--json", o.json, "print the final counters as one JSON object");
  cli.add_flag("--quiet", o.quiet, "no progress line");
  cli.add_trust(o.trust);
  cli.add_config_file();
  if (auto code = cli.parse(argc, argv)) return code;
  if (o.all == !o.streams.empty()) return cli.usage_error("name the streams to record or pass --all (not both)");
  return std::nullopt;
}

// Every image and point stream that exists now (--all); the others are said and skipped.
std::vector<std::string> every_recordable_stream(const sim::Trust& trust, sim::apps::StatusLine& status) {
  std::vector<std::string> streams;
  for (const auto& name : sim::list_streams()) {
    auto reader = sim::Reader::open(name, {.trust = trust});
    if (reader && sim::ros2::message_type_for(reader->layout())) {
      streams.push_back(name);
    } else {
      status.note("skipping " + name + " (" +
                  (reader ? std::string("raw bytes have no ROS 2 message") : reader.error().message) + ")");
    }
  }
  return streams;
}

// Waits until every named stream exists (--wait-for-streams); false when stopped meanwhile.
bool wait_for_streams(const std::vector<std::string>& streams, const sim::apps::StopSignal& stop) {
  for (const auto& name : streams) {
    while (!stop.requested()) {
      auto found = sim::inspect(name);
      if (found || found.error().code != sim::ErrorCode::not_found) break;  // start() says why
      stop.sleep_for(std::chrono::milliseconds(5));
    }
  }
  return !stop.requested();
}

// Records until stopped, the recording fails or --duration passed, with a progress line; returns
// the seconds it recorded.
double record_until_stopped(const sim::record::Recorder& recorder, double duration_s,
                            const sim::apps::StopSignal& stop, sim::apps::StatusLine& status) {
  const std::int64_t start = sim::monotonic_ns();
  const std::int64_t end = duration_s > 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
  while (!stop.requested() && !recorder.failed() && sim::monotonic_ns() < end) {
    stop.sleep_until(std::min(end, sim::monotonic_ns() + 100'000'000));
    if (status.due()) {
      const auto p = recorder.progress();
      status.update(sim::apps::fields(
          {{"recording", sim::apps::number(static_cast<double>(sim::monotonic_ns() - start) / 1e9) + " s"},
           {"frames", std::to_string(total(p, &StreamCounters::frames))},
           {"file", sim::apps::number(static_cast<double>(p.file_bytes) / 1e6) + " MB"},
           {"missed", std::to_string(total(p, &StreamCounters::missed))},
           {"queued", sim::apps::number(static_cast<double>(p.queued_bytes) / 1e6) + " MB"}}));
    }
  }
  return static_cast<double>(sim::monotonic_ns() - start) / 1e9;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_record",
      "Record SIM streams into an MCAP file (ROS 2 profile: PointCloud2, Image and "
      "CompressedImage in CDR) that Foxglove, rosbag2 and the mcap CLI read and sim_play "
      "replays. Stop it with Ctrl-C or --duration.");
  RecordOptions o;
  if (auto code = parse_command_line(cli, argc, argv, o)) return *code;

  auto& stop = sim::apps::StopSignal::install();
  sim::apps::StatusLine status = sim::apps::StatusLine::for_stderr("sim_record", o.quiet);
  if (o.all) {
    o.streams = every_recordable_stream(o.trust, status);
    if (o.streams.empty()) return cli.fail("no image or point stream exists; start a driver or a replay first");
  }
  if (o.wait_for_streams && !wait_for_streams(o.streams, stop)) return sim::apps::kExitOk;

  sim::record::RecorderOptions options;
  options.path = o.output;
  options.streams = o.streams;
  options.trust = o.trust;
  options.writer.library = "sim_record";
  options.writer.compression = *sim::mcap::parse_compression(o.compression);
  options.writer.chunk_size = o.chunk_kib * 1024;
  auto recorder = sim::record::Recorder::start(options);
  if (!recorder) return cli.fail(recorder.error());
  std::printf("recording %zu stream%s to %s (%s)\n", o.streams.size(), o.streams.size() == 1 ? "" : "s",
              o.output.c_str(), o.compression.c_str());
  std::fflush(stdout);

  const double seconds = record_until_stopped(*recorder, o.duration_s, stop, status);
  const auto result = recorder->stop();
  const std::string problem = recorder->problem();
  status.finish(sim::apps::fields({{"frames", std::to_string(total(result, &StreamCounters::frames))},
                                   {"missed", std::to_string(total(result, &StreamCounters::missed))}}));
  print_result(result, o.output, o.compression, seconds, problem, o.json);
  if (const auto missed = total(result, &StreamCounters::missed); missed > 0) {
    status.note(std::to_string(missed) + " frames were missed because the recorder fell behind; "
                "try --compression lz4 or none, or a faster disk");
  }
  if (!problem.empty()) status.note(problem);
  return recorder->failed() ? sim::apps::kExitFailure : sim::apps::kExitOk;
}
