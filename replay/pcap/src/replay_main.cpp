// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap: replays a Hesai capture into a SIM stream through the same LidarStream
// (decoder, frame assembler, writer) as the live driver, paced by the capture's timestamps.
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <optional>
#include <span>
#include <string>

#include "pacer.hpp"
#include "sim/clock.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/stream_options.hpp"
#include "sim/pcap/capture.hpp"

namespace {

std::atomic<bool> stop_requested{false};

void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a sleeping pacer wakes up
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

struct ReplayOptions {
  std::string file;
  std::optional<std::uint16_t> port;
  std::string filter;
  double rate = 1.0;
  bool max_rate = false;
  bool loop = false;
  double start_s = 0.0;
  double duration_s = 0.0;  // 0: to the end
  bool restamp = false;
  bool summary = false;
  bool quiet = false;
};

std::span<const std::uint8_t> as_u8(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()};
}

int fail(const std::string& message) {
  std::fprintf(stderr, "sim_replay_pcap: %s\n", message.c_str());
  return 1;
}

// What the first Hesai packet of the capture says: its model and its number of returns.
struct Detected {
  sim::hesai::Model model;
  unsigned returns = 1;
};

// Reads the capture up to its first Hesai packet (of `forced` when given). The error explains
// what the capture holds instead.
sim::Expected<Detected> detect(const ReplayOptions& r, sim::pcap::CaptureOptions options,
                               std::optional<sim::hesai::Model> forced) {
  auto reader = sim::pcap::CaptureReader::open(r.file, options);
  if (!reader) return reader.error();
  sim::pcap::Datagram datagram;
  std::optional<sim::hesai::Model> other;
  std::uint64_t seen = 0;
  for (;;) {
    const sim::pcap::NextStatus status = reader->next(datagram);
    if (status == sim::pcap::NextStatus::error) return reader->error();
    if (status == sim::pcap::NextStatus::end) break;
    ++seen;
    const auto model = sim::hesai::detect_model(as_u8(datagram.payload));
    if (!model) continue;
    if (forced && *model != *forced) {
      other = model;
      continue;
    }
    const auto returns = sim::hesai::returns_in(as_u8(datagram.payload), *model);
    return Detected{*model, returns.value_or(1)};
  }
  const auto& stats = reader->stats();
  const std::string on_port = r.port ? " on UDP port " + std::to_string(*r.port) : "";
  if (seen == 0) {
    return sim::Error{sim::ErrorCode::invalid_argument,
                      r.file + " holds " + std::to_string(stats.records) +
                          " packets but no UDP datagram" + on_port +
                          " (" + std::to_string(stats.not_udp) + " are IP but not UDP, " +
                          std::to_string(stats.not_ip) + " are not IP): it is not a LiDAR "
                          "capture" + (r.port ? ", or the sensor used another port (drop --port)." : ".")};
  }
  if (other) {
    return sim::Error{sim::ErrorCode::invalid_argument,
                      r.file + " holds " + std::string(sim::hesai::to_string(*other)) +
                          " packets, not " + std::string(sim::hesai::to_string(*forced)) +
                          "; give the right --model or leave it out to detect it."};
  }
  return sim::Error{sim::ErrorCode::invalid_argument,
                    "none of the " + std::to_string(seen) + " UDP datagrams" + on_port + " in " +
                        r.file + " is a Hesai point-cloud packet (models: " +
                        std::string(sim::hesai::model_names()) +
                        "); check the file, or choose the sensor's port with --port."};
}

class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled) {}
  void update(double fraction, std::uint64_t packets, std::uint64_t frames, unsigned pass,
              bool force = false) {
    if (!enabled_) return;
    const std::int64_t now = sim::monotonic_ns();
    if (start_ns_ == 0) start_ns_ = now;
    if (!force && now - last_ns_ < 200'000'000) return;
    last_ns_ = now;
    const double seconds = static_cast<double>(now - start_ns_) / 1e9;
    const double packet_rate = seconds > 0 ? static_cast<double>(packets) / seconds : 0.0;
    const double frame_rate = seconds > 0 ? static_cast<double>(frames) / seconds : 0.0;
    std::string percent = fraction >= 0 ? std::to_string(static_cast<int>(std::lround(std::min(fraction, 1.0) * 100))) + "%" : "";
    std::fprintf(stderr, "\r\033[K%s%s  %llu packets  %llu frames  %.0f pkt/s  %.1f frames/s",
                 pass > 1 ? ("pass " + std::to_string(pass) + "  ").c_str() : "", percent.c_str(),
                 static_cast<unsigned long long>(packets), static_cast<unsigned long long>(frames),
                 packet_rate, frame_rate);
    std::fflush(stderr);
  }
  void done() {
    if (enabled_ && start_ns_ != 0) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::int64_t start_ns_ = 0;
  std::int64_t last_ns_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ReplayOptions r;
  sim::hesai::StreamOptions s;
  CLI::App app{
      "Replays a Hesai LiDAR capture (pcap or pcapng) into a SIM stream, through the same "
      "decoder and frame assembler as the live driver sim_lidar_hesai, paced by the capture's "
      "timestamps.\nExit codes: 0 done (or stopped by a signal), 1 failure, 2 usage error.",
      "sim_replay_pcap"};
  app.add_option("file", r.file, "capture file (.pcap or .pcapng; Ethernet, VLAN, SLL, raw IP)")
      ->required()
      ->type_name("FILE");
  sim::hesai::add_stream_options(app, s);
  app.add_option("--port", r.port, "replay only UDP datagrams to or from this port [all]")
      ->type_name("N");
  app.add_option("--filter", r.filter, "extra BPF filter in tcpdump syntax, e.g. \"src host 192.168.1.201\"")
      ->type_name("EXPR");
  auto* rate = app.add_option("--rate", r.rate, "speed factor: 2 replays twice as fast [1]")
                   ->check(CLI::PositiveNumber);
  app.add_flag("--max-rate", r.max_rate, "as fast as possible, no pacing")->excludes(rate);
  app.add_flag("--loop", r.loop, "start over at the end of the capture until stopped");
  app.add_option("--start", r.start_s, "skip the first S seconds of the capture")
      ->check(CLI::NonNegativeNumber)
      ->type_name("S");
  app.add_option("--duration", r.duration_s, "replay only D seconds of the capture [to the end]")
      ->check(CLI::PositiveNumber)
      ->type_name("D");
  app.add_flag("--restamp", r.restamp,
               "publish stamps of the present (sensor time shifted to the replay's start) "
               "instead of the capture's");
  app.add_flag("--summary", r.summary,
               "print one line of counters at the end: summary frames=… packets=… lost=… "
               "malformed=…");
  app.add_flag("--quiet", r.quiet, "no progress line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  if (s.config.calibration.empty()) {
    std::fprintf(stderr, "sim_replay_pcap: no calibration file given; pass the recorded unit's "
                         "angle-correction CSV with --calibration (every unit has its own).\n");
    return 2;
  }
  s.config.heartbeat_period = std::chrono::milliseconds(500);

  sim::pcap::CaptureOptions capture_options;
  capture_options.port = r.port;
  capture_options.filter = r.filter;

  auto detected = detect(r, capture_options, s.model);
  if (!detected) return fail(detected.error().message);
  s.config.assembler.model = detected->model;
  s.config.returns = std::max(s.config.returns, detected->returns);

  auto stream = sim::hesai::LidarStream::create(s.config);
  if (!stream) return fail(stream.error().message);
  if (auto placed = sim::hesai::apply_thread_placement(s); !placed) return fail(placed.error().message);
  install_signal_handlers();

  sim::pcap::Pacer pacer(r.max_rate ? 0.0 : r.rate);
  Progress progress(!r.quiet && isatty(STDERR_FILENO) != 0);
  const auto start_ns = static_cast<std::int64_t>(r.start_s * 1e9);
  const auto end_ns = r.duration_s > 0 ? start_ns + static_cast<std::int64_t>(r.duration_s * 1e9)
                                       : INT64_MAX;
  std::uint64_t datagrams = 0;
  std::uint64_t skipped = 0;
  unsigned pass = 0;
  bool restamped = false;
  std::optional<std::string> read_error;
  for (;;) {
    ++pass;
    auto reader = sim::pcap::CaptureReader::open(r.file, capture_options);
    if (!reader) return fail(reader.error().message);
    const std::uint64_t packets_before = stream->counters().packets;
    std::optional<std::int64_t> first_ts;
    std::int64_t last_ts = 0;
    std::int64_t last_seen_ts = 0;
    std::uint64_t in_window = 0;
    sim::pcap::Datagram datagram;
    sim::pcap::NextStatus status;
    while ((status = reader->next(datagram)) == sim::pcap::NextStatus::datagram) {
      if (!first_ts) first_ts = datagram.timestamp_ns;
      last_seen_ts = datagram.timestamp_ns;
      const std::int64_t since_first = datagram.timestamp_ns - *first_ts;
      if (since_first < start_ns) continue;
      if (since_first > end_ns) break;
      last_ts = datagram.timestamp_ns;
      ++in_window;
      if (!pacer.wait(datagram.timestamp_ns, stop_requested)) break;
      if (r.restamp && !restamped) {
        // Shift the sensor's clock so the first packet's time is now; a loop adds to it below.
        sim::hesai::Packet packet;
        if (sim::hesai::Packet::parse(as_u8(datagram.payload), stream->model(), packet) ==
            sim::hesai::PacketError::none) {
          stream->set_stamp_offset(sim::realtime_ns() - packet.time_ns());
          restamped = true;
        }
      }
      stream->push(as_u8(datagram.payload), sim::realtime_ns());
      const double fraction =
          r.duration_s > 0 ? static_cast<double>(since_first - start_ns) / static_cast<double>(end_ns - start_ns)
                           : reader->progress();
      progress.update(fraction, stream->counters().packets, stream->published().frames, pass);
    }
    datagrams += reader->stats().datagrams;
    skipped += reader->stats().skipped();
    if (status == sim::pcap::NextStatus::error) {
      read_error = reader->error().message;
      break;
    }
    if (pass == 1 && in_window == 0 && first_ts && (start_ns > 0 || r.duration_s > 0)) {
      char message[512];
      std::snprintf(message, sizeof message,
                    "the window from --start %.3f s of %s holds no packet (the capture lasts "
                    "%.3f s); choose an earlier --start.",
                    r.start_s, r.file.c_str(), static_cast<double>(last_seen_ts - *first_ts) / 1e9);
      return fail(message);
    }
    const bool decoded_any = stream->counters().packets > packets_before;
    if (!r.loop || stop_requested.load() || !decoded_any || !first_ts) break;
    // Continue the schedule one mean packet interval after the last packet of this pass.
    const std::int64_t span = last_ts - (*first_ts + start_ns);
    const std::int64_t gap = in_window > 1 ? span / static_cast<std::int64_t>(in_window - 1) : 0;
    const std::int64_t shift = std::max<std::int64_t>(span + gap, 0);
    pacer.shift(shift);
    // The next pass starts mid-revolution: drop the revolution in progress. Its sensor times
    // start over too: shift the stamps so they keep increasing as a sensor's would.
    stream->reset();
    stream->set_stamp_offset(stream->stamp_offset() + shift);
  }
  stream->finish();
  progress.update(1.0, stream->counters().packets, stream->published().frames, pass, true);
  progress.done();

  if (r.summary) {
    std::printf("summary %s datagrams=%llu skipped=%llu passes=%u\n",
                stream->describe_counters(true).c_str(), static_cast<unsigned long long>(datagrams),
                static_cast<unsigned long long>(skipped), pass);
    std::fflush(stdout);
  }
  if (read_error) {
    return fail(*read_error + " " + std::to_string(stream->published().frames) +
                " frames were published before the damage.");
  }
  if (!stop_requested.load() && stream->counters().packets == 0) {
    return fail("no packet of " + r.file + " could be decoded as " +
                std::string(sim::hesai::to_string(stream->model())) + " (" +
                stream->describe_counters() + "); check --model and the capture.");
  }
  return 0;
}
