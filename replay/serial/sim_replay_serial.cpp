// SPDX-License-Identifier: Apache-2.0
// sim_replay_serial: replays a raw byte-stream recording of a Unitree LiDAR (what
// `sim_lidar_unitree --record` wrote, or any capture of the serial line) into SIM through the
// same decoder as the live driver. Frames are stamped with the host time they are published.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"
#include "sim/apps/pacer.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/sim_sink.hpp"

namespace {

// Publishes scans no faster than a scan rate, as the sensor would, on the shared absolute
// schedule; 0 Hz: as fast as possible. A stop request ends the wait and the replay.
class PacedSink final : public sim::unitree::ScanSink {
 public:
  PacedSink(sim::unitree::ScanSink& inner, double rate_hz, const sim::apps::StopSignal& stop)
      : inner_(inner), pacer_(rate_hz > 0 ? 1.0 : 0.0), stop_(stop),
        period_ns_(rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0) {}
  std::span<sim::LidarPoint> begin_scan() override { return inner_.begin_scan(); }
  void end_scan(std::size_t points, std::int64_t, std::int64_t receive_ns) override {
    if (!pacer_.wait(scans_ * period_ns_, stop_)) return;  // stopping: the scan is dropped
    ++scans_;
    inner_.end_scan(points, sim::realtime_ns(), receive_ns);
  }
  void imu(const sim::unitree::ImuSample& sample) override {
    sim::unitree::ImuSample s = sample;
    s.stamp_ns = sim::realtime_ns();
    inner_.imu(s);
  }
  // Stamped with this host's clock when published: host time, judged as such.
  void packet_time(std::int64_t, std::int64_t host_ns) override { inner_.packet_time(host_ns, host_ns); }

 private:
  sim::unitree::ScanSink& inner_;
  sim::apps::Pacer pacer_;
  const sim::apps::StopSignal& stop_;
  std::int64_t period_ns_;
  std::int64_t scans_ = 0;
};

struct Options {
  std::string path;
  std::string model_text;
  std::string stream;
  std::string imu_stream;
  bool no_imu = false;
  std::uint32_t scan_packets = 18;
  double rate_hz = 10.0;
  bool quiet = false;
  sim::ThreadPlacement placement;
  sim::apps::SensorOptions sensor;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  auto& app = cli.app();
  app.add_option("file", o.path, "the recording")->required();
  app.add_option("--model", o.model_text, "L1 or L2")->required()->check(
      sim::apps::validator(sim::unitree::model_problem, "Unitree model"));
  cli.add_stream("--stream", o.stream, "SIM point stream, e.g. /lidar_top")->required();
  cli.add_stream("--imu-stream", o.imu_stream, "SIM IMU stream (empty: <stream>.imu)");
  app.add_flag("--no-imu", o.no_imu, "do not publish IMU samples");
  app.add_option("--scan-packets", o.scan_packets, "packets per published scan")
      ->check(CLI::Range(1U, 1000U));
  app.add_option("--rate-hz", o.rate_hz, "scans per second to publish (0: as fast as possible)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("-q,--quiet", o.quiet, "no progress line and no summary");
  sim::apps::add_sensor_options(cli, o.sensor, sim::apps::SensorKind::lidar);
  cli.add_placement(o.placement);
}

// The streams the decoder's scans and IMU samples go to, described as a replay.
sim::unitree::SimSinkOptions sink_options(const Options& o, const sim::SensorInfo& described,
                                          const sim::unitree::DecoderOptions& decoder) {
  sim::unitree::SimSinkOptions sink;
  sink.points_stream = o.stream;
  sink.imu_stream = o.no_imu ? std::string()
                             : (o.imu_stream.empty() ? sim::unitree::default_imu_stream(o.stream)
                                                     : o.imu_stream);
  sink.max_points = sim::unitree::Decoder::max_points_per_scan(decoder);
  sink.sensor = sim::unitree::describe_sensor(described, decoder);
  sim::apps::describe_stamped_on_publish(*sink.sensor);
  sink.clock_base = sim::lidar::ClockBase::restamped;  // host time: source host, stamps host_arrival
  return sink;
}

// Feeds the recording to the decoder in chunks until its end or a stop, with the share read on
// the status line.
void replay_bytes(std::ifstream& in, std::uintmax_t total, sim::unitree::Decoder& decoder,
                  sim::unitree::SimScanSink& sink, sim::apps::StatusLine& status,
                  const sim::apps::StopSignal& stop) {
  std::vector<char> chunk(16384);
  std::uint64_t done = 0;
  while (in && !stop.requested()) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n == 0) break;
    decoder.push(std::as_bytes(std::span(chunk).first(n)), sim::realtime_ns());
    sink.tick_clock(sim::realtime_ns());
    done += n;
    status.update(sim::apps::number(total ? 100.0 * static_cast<double>(done) /
                                                static_cast<double>(total)
                                          : 100.0, 0) +
                  "%  " + sim::unitree::format_status(decoder.counters(), sink.counters()));
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
  auto described = sim::apps::sensor_info_from(o.sensor, o.stream);
  if (!described) return cli.fail(described.error());
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(o.placement)) return *code;

  const auto model = *sim::unitree::parse_model(o.model_text);
  std::ifstream in(o.path, std::ios::binary);
  std::error_code size_ec;
  const auto total = std::filesystem::file_size(o.path, size_ec);
  if (!in || size_ec) return cli.fail("cannot read '" + o.path + "'; check the path");

  sim::unitree::DecoderOptions options;
  options.model = model;
  options.packets_per_scan = o.scan_packets;
  auto sink = sim::unitree::SimScanSink::create(sink_options(o, *described, options));
  if (!sink) return cli.fail(sink.error());
  PacedSink paced(**sink, o.rate_hz, stop);
  sim::unitree::Decoder decoder(options, paced);

  auto status = sim::apps::StatusLine::for_stderr("sim_replay_serial", o.quiet);
  replay_bytes(in, total, decoder, **sink, status, stop);
  if (!stop.requested()) decoder.finish();
  (*sink)->tick_clock(sim::realtime_ns(), true);  // even a short recording leaves its verdict
  const auto counters = decoder.counters();
  status.finish(sim::unitree::format_status(counters, (*sink)->counters()));
  if (counters.framing.packets == 0 && !stop.requested()) {
    return cli.fail("no Unitree " + std::string(sim::unitree::to_string(model)) +
                    " packets with a good checksum in '" + o.path +
                    "'; check it is a raw byte recording of that model");
  }
  return sim::apps::kExitOk;
}
