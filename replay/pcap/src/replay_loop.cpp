// SPDX-License-Identifier: Apache-2.0
#include "replay_loop.hpp"

#include <algorithm>
#include <cstdio>

#include "sim/apps/pacer.hpp"
#include "sim/apps/status_line.hpp"

namespace sim::pcap {

CaptureOptions ReplayArgs::capture_options() const {
  CaptureOptions options;
  options.port = port;
  options.filter = filter;
  return options;
}

void add_replay_options(apps::CommandLine& cli, ReplayArgs& r) {
  auto& app = cli.app();
  app.add_option("file", r.file, "capture file (.pcap or .pcapng; Ethernet, VLAN, SLL, raw IP)")
      ->required()
      ->type_name("FILE");
  app.add_option("--port", r.port, "replay only UDP datagrams to or from this port (empty: all)")
      ->type_name("N");
  app.add_option("--filter", r.filter,
                 "extra BPF filter in tcpdump syntax, e.g. \"src host 192.168.1.201\"")
      ->type_name("EXPR");
  auto* rate = app.add_option("--rate", r.rate, "speed factor: 2 replays twice as fast")
                   ->check(CLI::PositiveNumber);
  app.add_flag("--max-rate", r.max_rate, "as fast as possible, no pacing")->excludes(rate);
  app.add_flag("--loop", r.loop,
               "start over at the end of the capture until stopped; every pass publishes the "
               "capture's whole revolutions (or scans), one sensor period apart across the wrap");
  app.add_option("--start", r.start_s, "skip the first S seconds of the capture")
      ->check(CLI::NonNegativeNumber)
      ->type_name("S");
  app.add_option("--duration", r.duration_s, "replay only D seconds of the capture (0: to the end)")
      ->check(CLI::NonNegativeNumber)
      ->type_name("D");
  app.add_flag("--restamp", r.restamp,
               "publish stamps of the present (sensor time shifted to the replay's start) "
               "instead of the capture's");
  app.add_flag("--summary", r.summary,
               "print one line of counters at the end: summary frames=... packets=... lost=...");
  app.add_flag("-q,--quiet", r.quiet, "no progress line");
}

namespace {

// Where frames end in the window, learnt on the first pass: the window index and capture time
// of the datagram that completed the first frame and of the one that completed the last.
struct FrameEnds {
  std::uint64_t frames = 0;
  std::uint64_t last_index = 0;
  std::int64_t first_ns = 0;
  std::int64_t last_ns = 0;

  void add(std::uint64_t index, std::int64_t capture_ns) {
    if (frames++ == 0) first_ns = capture_ns;
    last_index = index;
    last_ns = capture_ns;
  }
  // The sensor's frame period as the capture shows it (needs two frames).
  std::int64_t period_ns() const {
    return frames > 1 ? (last_ns - first_ns) / static_cast<std::int64_t>(frames - 1) : 0;
  }
};

}  // namespace

ReplayResult replay(const ReplayArgs& r, ReplayTarget& target, const apps::StopSignal& stop,
                    const std::string& tool) {
  ReplayResult result;
  apps::Pacer pacer(r.max_rate ? 0.0 : r.rate);
  auto status = apps::StatusLine::for_stderr(tool, r.quiet);
  const auto start_ns = static_cast<std::int64_t>(r.start_s * 1e9);
  const auto end_ns = r.duration_s > 0 ? start_ns + static_cast<std::int64_t>(r.duration_s * 1e9)
                                       : INT64_MAX;
  // Every pass publishes exactly the frames of the first, and nothing else. A later pass starts
  // from a fresh decoder at the window's start, as the first did (the datagrams before the first
  // boundary only lead into the first frame: a partial revolution is never published), and
  // stops at the datagram that completed the first pass's last frame (the frame cut short by
  // the end of the capture is left out). Splicing the capture's end onto its start instead would
  // publish revolutions that never existed: the points of one pass's last packets in the next
  // pass's first revolution.
  FrameEnds ends;
  for (;;) {
    ++result.passes;
    auto reader = CaptureReader::open(r.file, r.capture_options());
    if (!reader) {
      result.read_error = reader.error().message;
      break;
    }
    const bool later_pass = result.passes > 1 && ends.frames > 0;
    const std::uint64_t packets_before = target.decoded_packets();
    std::optional<std::int64_t> first_ts;
    std::int64_t window_first_ts = 0;
    std::int64_t last_ts = 0;
    std::int64_t last_seen_ts = 0;
    std::uint64_t in_window = 0;
    Datagram datagram;
    NextStatus next;
    while ((next = reader->next(datagram)) == NextStatus::datagram) {
      if (!first_ts) first_ts = datagram.timestamp_ns;
      last_seen_ts = datagram.timestamp_ns;
      const std::int64_t since_first = datagram.timestamp_ns - *first_ts;
      if (since_first < start_ns) continue;
      if (since_first > end_ns) break;
      const std::uint64_t index = in_window++;
      if (later_pass && index > ends.last_index) break;
      if (index == 0) window_first_ts = datagram.timestamp_ns;
      last_ts = datagram.timestamp_ns;
      if (!pacer.wait(datagram.timestamp_ns, stop)) break;
      const bool completed = target.push(datagram.payload, datagram.timestamp_ns);
      if (completed && result.passes == 1) ends.add(index, datagram.timestamp_ns);
      const double fraction =
          r.duration_s > 0 ? static_cast<double>(since_first - start_ns) /
                                 static_cast<double>(end_ns - start_ns)
                           : reader->progress();
      status.update(apps::fields({{"pass", std::to_string(result.passes)},
                                  {"done", apps::number(std::min(fraction, 1.0) * 100, 0) + "%"}}) +
                    "  " + target.status());
    }
    result.datagrams += reader->stats().datagrams;
    result.skipped += reader->stats().skipped();
    if (next == NextStatus::error) {
      result.read_error = reader->error().message;
      break;
    }
    if (result.passes == 1 && in_window == 0 && first_ts && (start_ns > 0 || r.duration_s > 0)) {
      result.empty_window = true;
      result.capture_span_s = static_cast<double>(last_seen_ts - *first_ts) / 1e9;
      break;
    }
    const bool decoded_any = target.decoded_packets() > packets_before;
    if (!r.loop || stop.requested() || !decoded_any || !first_ts) break;
    // How far the next pass is moved on, on the schedule and in the stamps.
    std::int64_t shift = 0;
    if (ends.frames > 1) {
      // A pass of n frames lasts n frame periods: the next pass's first frame comes one period
      // after this pass's last, so a 10 Hz sensor replays at 10 Hz. The datagrams that only lead
      // into that frame fall due about when this pass ended and go out at once.
      shift = ends.period_ns() * static_cast<std::int64_t>(ends.frames);
    } else {
      // One frame or none: the next pass follows this one as recorded, one datagram interval
      // after its last.
      const std::int64_t span = last_ts - window_first_ts;
      const std::uint64_t replayed = later_pass ? ends.last_index + 1 : in_window;
      const std::int64_t gap =
          replayed > 1 ? span / static_cast<std::int64_t>(replayed - 1) : 0;
      shift = std::max<std::int64_t>(span + gap, 0);
    }
    target.restart();
    pacer.shift(shift);
    target.shift_stamps(shift);
  }
  target.finish();
  status.finish(target.status());
  return result;
}

}  // namespace sim::pcap
