// SPDX-License-Identifier: Apache-2.0
// sim_echo: prints the frames of a stream as JSON lines, or their rate and latency (--stats).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim_tools/cli.hpp"

namespace {

std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true); }

// Rate, latency and skips over one reporting interval (and over the whole run).
struct Window {
  std::uint64_t frames = 0;
  std::uint64_t skipped = 0;
  std::vector<double> latencies_us;
  std::uint64_t last_size = 0;

  void add(double latency_us, std::uint64_t size) {
    ++frames;
    latencies_us.push_back(latency_us);
    last_size = size;
  }
  double percentile(double p) {
    if (latencies_us.empty()) return 0;
    const auto k = static_cast<std::size_t>(p * static_cast<double>(latencies_us.size() - 1));
    std::nth_element(latencies_us.begin(), latencies_us.begin() + static_cast<long>(k),
                     latencies_us.end());
    return latencies_us[k];
  }
  double mean() const {
    double sum = 0;
    for (const double v : latencies_us) sum += v;
    return latencies_us.empty() ? 0 : sum / static_cast<double>(latencies_us.size());
  }
  double max() const {
    return latencies_us.empty() ? 0 : *std::max_element(latencies_us.begin(), latencies_us.end());
  }
  double min() const {
    return latencies_us.empty() ? 0 : *std::min_element(latencies_us.begin(), latencies_us.end());
  }
};

void print_stats(const char* label, const std::string& name, Window& w, double rate) {
  std::printf(
      "{\"%s\":\"%s\",\"frames\":%llu,\"skipped\":%llu,\"rate_hz\":%.2f,\"size\":%llu,"
      "\"latency_us\":{\"min\":%.1f,\"mean\":%.1f,\"p50\":%.1f,\"p99\":%.1f,\"max\":%.1f}}\n",
      label, name.c_str(), static_cast<unsigned long long>(w.frames),
      static_cast<unsigned long long>(w.skipped), rate,
      static_cast<unsigned long long>(w.last_size), w.min(), w.mean(), w.percentile(0.5),
      w.percentile(0.99), w.max());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Print the frames of a SIM stream, one JSON line each (seq, stamp, size, latency, "
               "layout), or with --stats its rate, latency and skipped frames."};
  std::string name;
  std::uint64_t count = 0;
  bool stats = false;
  double interval_s = 1.0;
  double timeout_s = 0;
  double duration_s = 0;
  bool wait_for_stream = false;
  bool poll = false;
  app.add_option("stream", name, "stream name, like /lidar_top")->required();
  app.add_option("--count,-n", count, "exit after this many frames");
  app.add_flag("--stats", stats, "print rate, latency and skips every --interval instead of frames");
  app.add_option("--interval", interval_s, "seconds between --stats lines")->check(CLI::PositiveNumber);
  app.add_option("--timeout", timeout_s, "fail (exit 1) when no frame arrives for this many seconds");
  app.add_option("--duration", duration_s, "stop after this many seconds");
  app.add_flag("--wait-for-stream", wait_for_stream, "wait until the stream exists");
  app.add_flag("--poll", poll, "busy-poll instead of sleeping until each frame (uses a core)");
  sim::tools::Placement placement;
  sim::tools::add_placement_options(app, placement);
  if (auto code = sim::tools::parse(app, argc, argv)) return *code;
  if (auto code = sim::tools::apply_placement(placement, "sim_echo")) return *code;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const std::int64_t start = sim::monotonic_ns();
  auto elapsed_s = [&] { return static_cast<double>(sim::monotonic_ns() - start) / 1e9; };

  auto reader = sim::Reader::open(name);
  while (!reader && wait_for_stream && reader.error().code == sim::ErrorCode::not_found &&
         !stop_requested.load() && (duration_s <= 0 || elapsed_s() < duration_s)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    reader = sim::Reader::open(name);
  }
  if (!reader) {
    std::fprintf(stderr, "sim_echo: %s\n", reader.error().message.c_str());
    return 1;
  }

  std::vector<std::byte> buffer(reader->capacity());
  Window window;
  Window total;
  std::int64_t window_start = sim::monotonic_ns();
  std::uint64_t skipped_before_window = 0;
  std::int64_t first_frame_at = 0;
  std::int64_t last_frame_at = sim::monotonic_ns();
  int exit_code = 0;
  const auto slice = std::chrono::milliseconds(100);

  while (!stop_requested.load()) {
    if (duration_s > 0 && elapsed_s() >= duration_s) break;
    sim::FrameInfo info;
    sim::ReadStatus status = poll ? reader->read(buffer, info) : reader->read_next(buffer, info, slice);
    if (status == sim::ReadStatus::buffer_too_small) {
      buffer.resize(reader->capacity());  // the writer recreated the stream with a larger layout
      continue;
    }
    const std::int64_t now = sim::monotonic_ns();
    if (status == sim::ReadStatus::new_frame) {
      last_frame_at = now;
      if (first_frame_at == 0) first_frame_at = now;
      const double latency_us = static_cast<double>(now - info.publish_ns) / 1e3;
      const sim::ReaderStats rs = reader->stats();
      window.skipped = rs.skipped - skipped_before_window;
      if (stats) {
        window.add(latency_us, info.size);
      } else {
        std::printf(
            "{\"seq\":%llu,\"stamp_ns\":%lld,\"receive_ns\":%lld,\"publish_ns\":%lld,"
            "\"size\":%llu,\"latency_us\":%.1f,\"skipped\":%llu,\"layout\":\"%s\"}\n",
            static_cast<unsigned long long>(info.seq), static_cast<long long>(info.stamp_ns),
            static_cast<long long>(info.receive_ns), static_cast<long long>(info.publish_ns),
            static_cast<unsigned long long>(info.size),
            latency_us, static_cast<unsigned long long>(rs.skipped),
            info.layout.describe().c_str());
        std::fflush(stdout);
      }
      total.add(latency_us, info.size);
      total.skipped = rs.skipped;
      if (count != 0 && total.frames >= count) break;
    } else if (status == sim::ReadStatus::region_invalid) {
      std::fprintf(stderr, "sim_echo: stream %s failed validation; restart its writer\n",
                   name.c_str());
      exit_code = 1;
      break;
    } else if (poll) {
      std::this_thread::yield();
    }
    if (timeout_s > 0 && static_cast<double>(now - last_frame_at) / 1e9 > timeout_s) {
      std::fprintf(stderr, "sim_echo: no frame on %s for %.1f s (writer %s)\n", name.c_str(),
                   timeout_s, reader->writer_alive() ? "alive" : "gone");
      exit_code = 1;
      break;
    }
    if (stats && static_cast<double>(now - window_start) / 1e9 >= interval_s) {
      const double window_s = static_cast<double>(now - window_start) / 1e9;
      print_stats("stream", name, window, static_cast<double>(window.frames) / window_s);
      window = Window{};
      skipped_before_window = reader->stats().skipped;
      window_start = now;
    }
  }
  if (stats) {
    // The rate of the whole run counts from the first frame, not from when the tool started.
    const double span_s = static_cast<double>(last_frame_at - first_frame_at) / 1e9;
    const double rate_hz =
        (total.frames > 1 && span_s > 0) ? static_cast<double>(total.frames - 1) / span_s : 0.0;
    print_stats("summary", name, total, rate_hz);
  }
  return exit_code;
}
