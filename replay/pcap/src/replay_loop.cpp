// SPDX-License-Identifier: Apache-2.0
#include "replay_loop.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

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
  cli.add_option("file", r.file, "capture file (.pcap or .pcapng; Ethernet, VLAN, SLL, raw IP)")
      .required()
      .type_name("FILE");
  cli.add_option("--port", r.port, "replay only UDP datagrams to or from this port (empty: all)")
      .type_name("N");
  cli.add_option("--filter", r.filter,
                 "extra BPF filter in tcpdump syntax, e.g. \"src host 192.168.1.201\"")
      .type_name("EXPR");
  const auto rate = cli.add_option("--rate", r.rate, "speed factor: 2 replays twice as fast").positive();
  cli.add_flag("--max-rate", r.max_rate, "as fast as possible, no pacing").excludes(rate);
  cli.add_flag("--loop", r.loop,
               "start over at the end of the capture until stopped; every pass publishes the "
               "capture's whole revolutions (or scans), one sensor period apart across the wrap");
  cli.add_option("--start", r.start_s, "skip the first S seconds of the capture")
      .non_negative()
      .type_name("S");
  cli.add_option("--duration", r.duration_s, "replay only D seconds of the capture (0: to the end)")
      .non_negative()
      .type_name("D");
  cli.add_flag("--restamp", r.restamp,
               "publish stamps of the present (sensor time shifted to the replay's start) "
               "instead of the capture's; the stream then says its time base is this host's clock");
  cli.add_flag("--summary", r.summary,
               "print one line of counters at the end: summary frames=... packets=... lost=...");
  cli.add_flag("-q,--quiet", r.quiet, "no progress line");
}

namespace {

// "192.168.1.201" of "192.168.1.201:2368", "fe80::1" of "[fe80::1]:2368".
std::string host_of(const Endpoint& endpoint) {
  std::string text = endpoint.to_string();
  text = text.substr(0, text.rfind(':'));
  if (!text.empty() && text.front() == '[') text = text.substr(1, text.size() - 2);
  return text;
}

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

// The part of the capture replayed (--start, --duration), in ns since its first datagram.
struct Window {
  std::int64_t start_ns;
  std::int64_t end_ns;

  explicit Window(const ReplayArgs& r)
      : start_ns(static_cast<std::int64_t>(r.start_s * 1e9)),
        end_ns(r.duration_s > 0 ? start_ns + static_cast<std::int64_t>(r.duration_s * 1e9) : INT64_MAX) {}
};

// What one pass through the capture saw.
struct Pass {
  NextStatus next = NextStatus::end;       // why it stopped reading (datagram: it left early)
  std::optional<std::int64_t> first_ts;    // the capture's first datagram
  std::int64_t last_seen_ts = 0;           // the last one read
  std::int64_t window_first_ts = 0;        // the first and last one replayed
  std::int64_t last_ts = 0;
  std::uint64_t in_window = 0;             // datagrams in the window
};

// Every pass publishes exactly the frames of the first, and nothing else. A later pass starts
// from a fresh decoder at the window's start, as the first did (the datagrams before the first
// boundary only lead into the first frame: a partial revolution is never published), and
// stops at the datagram that completed the first pass's last frame (the frame cut short by
// the end of the capture is left out). Splicing the capture's end onto its start instead would
// publish revolutions that never existed: the points of one pass's last packets in the next
// pass's first revolution.
class Replayer {
 public:
  Replayer(const ReplayArgs& r, ReplayTarget& target, const apps::StopSignal& stop, const std::string& tool)
      : r_(r),
        target_(target),
        stop_(stop),
        window_(r),
        pacer_(r.max_rate ? 0.0 : r.rate),
        status_(apps::StatusLine::for_stderr(tool, r.quiet)) {}

  ReplayResult run() {
    for (;;) {
      ++result_.passes;
      auto reader = CaptureReader::open(r_.file, r_.capture_options());
      if (!reader) {
        result_.read_error = reader.error().message;
        break;
      }
      const bool later_pass = result_.passes > 1 && ends_.frames > 0;
      const std::uint64_t packets_before = target_.decoded_packets();
      const Pass pass = play_pass(*reader, later_pass);
      result_.datagrams += reader->stats().datagrams;
      result_.skipped += reader->stats().skipped();
      if (pass.next == NextStatus::error) {
        result_.read_error = reader->error().message;
        break;
      }
      if (result_.passes == 1 && pass.in_window == 0 && pass.first_ts &&
          (window_.start_ns > 0 || r_.duration_s > 0)) {
        result_.empty_window = true;
        result_.capture_span_s = static_cast<double>(pass.last_seen_ts - *pass.first_ts) / 1e9;
        break;
      }
      const bool decoded_any = target_.decoded_packets() > packets_before;
      if (!r_.loop || stop_.requested() || !decoded_any || !pass.first_ts) break;
      const std::int64_t shift = next_pass_shift(pass, later_pass);
      target_.restart();
      pacer_.shift(shift);
      target_.shift_stamps(shift);
    }
    target_.finish();
    status_.finish(target_.status());
    return result_;
  }

 private:
  // The window's datagrams, paced, into the target; the first pass learns where frames end, a
  // later one stops where the first pass's last frame ended.
  Pass play_pass(CaptureReader& reader, bool later_pass) {
    Pass pass;
    Datagram datagram;
    while ((pass.next = reader.next(datagram)) == NextStatus::datagram) {
      if (!pass.first_ts) pass.first_ts = datagram.timestamp_ns;
      pass.last_seen_ts = datagram.timestamp_ns;
      const std::int64_t since_first = datagram.timestamp_ns - *pass.first_ts;
      if (since_first < window_.start_ns) continue;
      if (since_first > window_.end_ns) break;
      const std::uint64_t index = pass.in_window++;
      if (later_pass && index > ends_.last_index) break;
      if (index == 0) pass.window_first_ts = datagram.timestamp_ns;
      pass.last_ts = datagram.timestamp_ns;
      if (!target_.takes(datagram)) {
        ++result_.skipped;
        continue;
      }
      if (!pacer_.wait(datagram.timestamp_ns, stop_)) break;
      const std::uint64_t decoded = target_.decoded_packets();
      const bool completed = target_.push(datagram);
      if (target_.decoded_packets() != decoded) count_sender(datagram.source);
      if (completed && result_.passes == 1) ends_.add(index, datagram.timestamp_ns);
      show_progress(reader, since_first);
    }
    return pass;
  }

  // A second sensor on the port is decoded with the first (one frame assembler for both):
  // counted, and said once, as the live drivers do.
  void count_sender(const Endpoint& source) {
    if (!first_sender_) {
      first_sender_ = source;
      return;
    }
    if (source.ip_version == first_sender_->ip_version && source.address == first_sender_->address) return;
    if (result_.other_senders++ != 0) return;
    status_.note("warning: packets from " + host_of(source) + " are decoded besides those from " +
                 host_of(*first_sender_) + ": two sensors on one port are decoded as one; choose one with "
                 "--filter \"src host " + host_of(*first_sender_) + "\"");
  }

  void show_progress(const CaptureReader& reader, std::int64_t since_first) {
    const double fraction = r_.duration_s > 0 ? static_cast<double>(since_first - window_.start_ns) /
                                                    static_cast<double>(window_.end_ns - window_.start_ns)
                                              : reader.progress();
    status_.update(apps::fields({{"pass", std::to_string(result_.passes)},
                                 {"done", apps::number(std::min(fraction, 1.0) * 100, 0) + "%"}}) +
                   "  " + target_.status() +
                   (result_.other_senders != 0 ? " other-senders " + std::to_string(result_.other_senders) : ""));
  }

  // How far the next pass is moved on, on the schedule and in the stamps.
  std::int64_t next_pass_shift(const Pass& pass, bool later_pass) const {
    if (ends_.frames > 1) {
      // A pass of n frames lasts n frame periods: the next pass's first frame comes one period
      // after this pass's last, so a 10 Hz sensor replays at 10 Hz. The datagrams that only lead
      // into that frame fall due about when this pass ended and go out at once.
      return ends_.period_ns() * static_cast<std::int64_t>(ends_.frames);
    }
    // One frame or none: the next pass follows this one as recorded, one datagram interval
    // after its last.
    const std::int64_t span = pass.last_ts - pass.window_first_ts;
    const std::uint64_t replayed = later_pass ? ends_.last_index + 1 : pass.in_window;
    const std::int64_t gap = replayed > 1 ? span / static_cast<std::int64_t>(replayed - 1) : 0;
    return std::max<std::int64_t>(span + gap, 0);
  }

  const ReplayArgs& r_;
  ReplayTarget& target_;
  const apps::StopSignal& stop_;
  const Window window_;
  apps::Pacer pacer_;
  apps::StatusLine status_;
  FrameEnds ends_;
  ReplayResult result_;
  std::optional<Endpoint> first_sender_;
};

}  // namespace

ReplayResult replay(const ReplayArgs& r, ReplayTarget& target, const apps::StopSignal& stop,
                    const std::string& tool) {
  return Replayer(r, target, stop, tool).run();
}

}  // namespace sim::pcap
