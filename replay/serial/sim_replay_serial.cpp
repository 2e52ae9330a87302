// SPDX-License-Identifier: Apache-2.0
// sim_replay_serial: replays a raw byte-stream recording of a Unitree LiDAR (what
// `sim_lidar_unitree --record` wrote, or any capture of the serial line) into SIM through the
// same decoder as the live driver. Frames are stamped with the host time they are published.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <sim_tools/cli.hpp>

#include "sim/clock.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/sim_sink.hpp"

namespace {

// Publishes scans no faster than a scan rate, as the sensor would; 0 Hz: as fast as possible.
class PacedSink final : public sim::unitree::ScanSink {
 public:
  PacedSink(sim::unitree::ScanSink& inner, double rate_hz) : inner_(inner) {
    if (rate_hz > 0) {
      period_ = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(1.0 / rate_hz));
    }
  }
  std::span<sim::LidarPoint> begin_scan() override { return inner_.begin_scan(); }
  void end_scan(std::size_t points, std::int64_t, std::int64_t receive_ns) override {
    if (period_.count() > 0) {
      if (next_ == std::chrono::steady_clock::time_point{}) next_ = std::chrono::steady_clock::now();
      std::this_thread::sleep_until(next_);
      next_ += period_;
    }
    inner_.end_scan(points, sim::realtime_ns(), receive_ns);
  }
  void imu(const sim::unitree::ImuSample& sample) override {
    sim::unitree::ImuSample s = sample;
    s.stamp_ns = sim::realtime_ns();
    inner_.imu(s);
  }

 private:
  sim::unitree::ScanSink& inner_;
  std::chrono::steady_clock::duration period_{0};
  std::chrono::steady_clock::time_point next_{};
};

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  std::string model_text;
  std::string stream;
  std::string imu_stream;
  bool no_imu = false;
  std::uint32_t scan_packets = 18;
  double rate_hz = 10.0;
  bool quiet = false;
  CLI::App app{
      "Replay a raw byte recording of a Unitree L1 or L2 (sim_lidar_unitree --record) into SIM."};
  app.add_option("file", path, "the recording")->required();
  app.add_option("--model", model_text, "L1 or L2")->required();
  app.add_option("--stream", stream, "SIM point stream, e.g. /lidar_top")->required();
  app.add_option("--imu-stream", imu_stream, "SIM IMU stream (default: <stream>.imu)");
  app.add_flag("--no-imu", no_imu, "do not publish IMU samples");
  app.add_option("--scan-packets", scan_packets, "packets per published scan")
      ->capture_default_str()
      ->check(CLI::Range(1U, 1000U));
  app.add_option("--rate-hz", rate_hz, "scans per second to publish (0: as fast as possible)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("-q,--quiet", quiet, "no progress line");
  sim::tools::Placement placement;
  sim::tools::add_placement_options(app, placement);
  if (auto code = sim::tools::parse(app, argc, argv)) return *code;
  if (auto code = sim::tools::apply_placement(placement, "sim_replay_serial")) return *code;

  const auto model = sim::unitree::parse_model(model_text);
  if (!model) {
    std::cerr << "sim_replay_serial: unknown model '" << model_text
              << "'; use --model L1 or --model L2.\n";
    return sim::tools::kExitUsage;
  }
  std::ifstream in(path, std::ios::binary);
  std::error_code size_ec;
  const auto total = std::filesystem::file_size(path, size_ec);
  if (!in || size_ec) {
    std::cerr << "sim_replay_serial: cannot read '" << path << "'; check the path.\n";
    return sim::tools::kExitFailure;
  }

  sim::unitree::DecoderOptions options;
  options.model = *model;
  options.packets_per_scan = scan_packets;
  sim::unitree::SimSinkOptions sink_options;
  sink_options.points_stream = stream;
  sink_options.imu_stream =
      no_imu ? std::string()
             : (imu_stream.empty() ? sim::unitree::default_imu_stream(stream) : imu_stream);
  sink_options.max_points = sim::unitree::Decoder::max_points_per_scan(options);
  auto sink = sim::unitree::SimScanSink::create(sink_options);
  if (!sink) {
    std::cerr << "sim_replay_serial: " << sink.error().message << "\n";
    return sink.error().code == sim::ErrorCode::invalid_name ? sim::tools::kExitUsage
                                                             : sim::tools::kExitFailure;
  }
  PacedSink paced(**sink, rate_hz);
  sim::unitree::Decoder decoder(options, paced);

  const bool progress = !quiet && ::isatty(STDERR_FILENO) != 0;
  std::vector<char> chunk(16384);
  std::uint64_t done = 0;
  auto last_print = std::chrono::steady_clock::now();
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n == 0) break;
    decoder.push(std::as_bytes(std::span(chunk).first(n)), sim::realtime_ns());
    done += n;
    if (progress && std::chrono::steady_clock::now() - last_print > std::chrono::milliseconds(250)) {
      last_print = std::chrono::steady_clock::now();
      std::fprintf(stderr, "\r%3.0f%%  %s\x1b[K", total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0,
                   sim::unitree::format_status(decoder.counters(), (*sink)->counters()).c_str());
    }
  }
  decoder.finish();
  const auto counters = decoder.counters();
  if (!quiet) {
    std::fprintf(stderr, "%s%s\n", progress ? "\r\x1b[K" : "",
                 sim::unitree::format_status(counters, (*sink)->counters()).c_str());
  }
  if (counters.framing.packets == 0) {
    std::cerr << "sim_replay_serial: no Unitree " << sim::unitree::to_string(*model)
              << " packets with a good checksum in '" << path
              << "'; check it is a raw byte recording of that model.\n";
    return sim::tools::kExitFailure;
  }
  return sim::tools::kExitOk;
}
