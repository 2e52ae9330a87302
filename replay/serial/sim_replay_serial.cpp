// SPDX-License-Identifier: Apache-2.0
// sim_replay_serial: replays a raw byte-stream recording of a Unitree LiDAR (what
// `sim_lidar_unitree --record` wrote, or any capture of the serial line) into SIM through the
// same LidarStream as the live driver. A byte recording holds no times of its own, so scans are
// published no faster than --rate-hz and stamped with the host time they are published.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"
#include "sim/apps/pacer.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/apps/unitree_options.hpp"
#include "sim/clock.hpp"
#include "sim/unitree/lidar_stream.hpp"

namespace {

struct Options {
  std::string path;
  sim::apps::UnitreeStreamOptions stream;
  double rate_hz = 10.0;
  bool quiet = false;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  cli.add_option("file", o.path, "the recording").required();
  sim::apps::add_unitree_stream_options(cli, o.stream, sim::apps::SensorTimeOption::not_offered);
  cli.add_option("--rate-hz", o.rate_hz, "scans per second to publish (0: as fast as possible)")
      .in_range(0.0, 1000.0);
  cli.add_flag("-q,--quiet", o.quiet, "no progress line and no summary");
}

// Publishes scans no faster than a scan rate, as the sensor would, on the shared absolute
// schedule (0 Hz: as fast as possible), each stamped when its turn comes. A stop request ends
// the wait and drops the scan.
class ScanPace {
 public:
  ScanPace(double rate_hz, const sim::apps::StopSignal& stop)
      : pacer_(rate_hz > 0 ? 1.0 : 0.0), stop_(&stop),
        period_ns_(rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0) {}
  std::optional<std::int64_t> operator()() {
    if (!pacer_.wait(scans_ * period_ns_, *stop_)) return std::nullopt;
    ++scans_;
    return sim::realtime_ns();
  }

 private:
  sim::apps::Pacer pacer_;
  const sim::apps::StopSignal* stop_;
  std::int64_t period_ns_;
  std::int64_t scans_ = 0;
};

// Feeds the recording to the stream in chunks until its end or a stop, with the share read on
// the status line. Each chunk arrives now: its packets are host time, judged as such.
void replay_bytes(std::ifstream& in, std::uintmax_t total, sim::unitree::LidarStream& stream,
                  sim::apps::StatusLine& status, const sim::apps::StopSignal& stop) {
  std::vector<std::uint8_t> chunk(16384);
  std::uint64_t done = 0;
  while (in && !stop.requested()) {
    in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n == 0) break;
    stream.push(std::span(chunk).first(n), sim::realtime_ns());
    stream.tick_clock(sim::realtime_ns());
    done += n;
    const double share = total != 0 ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0;
    status.update(sim::apps::number(share, 0) + "%  " + stream.describe_counters());
  }
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_replay_serial",
      "Replay a raw byte recording of a Unitree L1 or L2 (sim_lidar_unitree --record) into SIM, "
      "through the same decoder as the live driver; scans are stamped when published.");
  Options o;
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  auto config = sim::apps::unitree_stream_config(o.stream);
  if (!config) return cli.fail(config.error());
  sim::apps::describe_stamped_on_publish(*config->sensor);
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;

  std::ifstream in(o.path, std::ios::binary);
  std::error_code size_ec;
  const auto total = std::filesystem::file_size(o.path, size_ec);
  if (!in || size_ec) return cli.fail("cannot read '" + o.path + "'; check the path");

  config->publish_gate = ScanPace(o.rate_hz, stop);
  auto stream = sim::unitree::LidarStream::create(*config);
  if (!stream) return cli.fail(stream.error());
  auto status = sim::apps::StatusLine::for_stderr("sim_replay_serial", o.quiet);
  replay_bytes(in, total, *stream, status, stop);
  if (!stop.requested()) stream->finish();
  stream->tick_clock(sim::realtime_ns(), true);  // even a short recording leaves its verdict
  status.finish(stream->describe_counters());
  if (stream->counters().framing.packets == 0 && !stop.requested()) {
    return cli.fail("no Unitree " + std::string(sim::unitree::to_string(stream->model())) +
                    " packets with a good checksum in '" + o.path + "'; check it is a raw byte recording of that model");
  }
  return sim::apps::kExitOk;
}
