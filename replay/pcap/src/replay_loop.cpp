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
               "start over at the end of the capture until stopped; later passes replay whole "
               "revolutions (or scans) only, so the frame rate stays the sensor's");
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

ReplayResult replay(const ReplayArgs& r, ReplayTarget& target, const apps::StopSignal& stop,
                    const std::string& tool) {
  ReplayResult result;
  apps::Pacer pacer(r.max_rate ? 0.0 : r.rate);
  auto status = apps::StatusLine::for_stderr(tool, r.quiet);
  const auto start_ns = static_cast<std::int64_t>(r.start_s * 1e9);
  const auto end_ns = r.duration_s > 0 ? start_ns + static_cast<std::int64_t>(r.duration_s * 1e9)
                                       : INT64_MAX;
  // Where frames end in the window, learnt on the first pass (datagram index and capture time):
  // later passes replay from the first frame boundary to the last, so the frame in progress at
  // the wrap continues into the next pass instead of being cut (a 0.4 s capture of a 10 Hz
  // sensor would otherwise lose a revolution at every wrap and show 5 Hz).
  std::optional<std::uint64_t> first_boundary;
  std::uint64_t last_boundary = 0;
  std::int64_t first_boundary_ts = 0;
  std::int64_t last_boundary_ts = 0;
  for (;;) {
    ++result.passes;
    auto reader = CaptureReader::open(r.file, r.capture_options());
    if (!reader) {
      result.read_error = reader.error().message;
      break;
    }
    const bool trimmed = result.passes > 1 && first_boundary && last_boundary > *first_boundary;
    const std::uint64_t packets_before = target.decoded_packets();
    std::optional<std::int64_t> first_ts;
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
      if (trimmed && index < *first_boundary) continue;
      if (trimmed && index >= last_boundary) break;
      last_ts = datagram.timestamp_ns;
      if (!pacer.wait(datagram.timestamp_ns, stop)) break;
      const bool completed = target.push(datagram.payload, datagram.timestamp_ns);
      if (completed && result.passes == 1) {
        if (!first_boundary) {
          first_boundary = index;
          first_boundary_ts = datagram.timestamp_ns;
        }
        last_boundary = index;
        last_boundary_ts = datagram.timestamp_ns;
      }
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
    std::int64_t shift = 0;
    if (first_boundary && last_boundary > *first_boundary) {
      if (result.passes == 1) {
        // The first pass ran to the end of the window: its unfinished frame is dropped once,
        // and the next pass begins at the first boundary, one packet interval later.
        const std::int64_t gap = in_window > 1
            ? (last_ts - (*first_ts + start_ns)) / static_cast<std::int64_t>(in_window - 1)
            : 0;
        shift = std::max<std::int64_t>(last_ts + gap - first_boundary_ts, 0);
        target.restart();
      } else {
        // The pass stopped just before the last boundary; the first boundary takes its place.
        shift = last_boundary_ts - first_boundary_ts;
      }
    } else {
      // No frame boundary seen (a window shorter than a frame): start over, as recorded.
      const std::int64_t span = last_ts - (*first_ts + start_ns);
      const std::int64_t gap =
          in_window > 1 ? span / static_cast<std::int64_t>(in_window - 1) : 0;
      shift = std::max<std::int64_t>(span + gap, 0);
      target.restart();
    }
    pacer.shift(shift);
    target.shift_stamps(shift);
  }
  target.finish();
  status.finish(target.status());
  return result;
}

}  // namespace sim::pcap
