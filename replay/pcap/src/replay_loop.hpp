// SPDX-License-Identifier: Apache-2.0
// The part of sim_replay_pcap every sensor family shares: the capture options, and the paced
// walk through the capture's window, pass after pass with --loop. A family plugs in as a
// ReplayTarget (decoder -> SIM stream); the loop knows nothing of packets.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/pcap/capture.hpp"

namespace sim::pcap {

struct ReplayArgs {
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

  CaptureOptions capture_options() const;
};

// file, --port, --filter, --rate, --max-rate, --loop, --start, --duration, --restamp,
// --summary, --quiet.
void add_replay_options(apps::CommandLine& cli, ReplayArgs& args);

class ReplayTarget {
 public:
  virtual ~ReplayTarget() = default;
  // Whether the family's route sends the datagram to one of its pushes (e.g. only to the ports
  // its metadata names); the others are skipped and counted. Asked before push().
  virtual bool takes(const Datagram&) { return true; }
  // The datagram into the push its route chooses, its capture time as its arrival; true when
  // it completed a frame (a revolution, a scan).
  virtual bool push(const Datagram& datagram) = 0;
  // The replay starts over (a loop): forget the frame in progress, as a fresh decoder would.
  virtual void restart() = 0;
  // Later datagrams were recorded `shift_ns` earlier than they are now replayed (loops):
  // stamps move by it so they keep increasing, as a sensor's would.
  virtual void shift_stamps(std::int64_t shift_ns) = 0;
  virtual void finish() = 0;
  virtual std::uint64_t decoded_packets() const = 0;
  virtual std::uint64_t frames() const = 0;
  // "packets 3600  frames 10  lost 0" for the status line; key=value pairs for --summary.
  virtual std::string status() const = 0;
  virtual std::string summary() const = 0;
};

struct ReplayResult {
  std::uint64_t datagrams = 0;
  std::uint64_t skipped = 0;
  // Decoded packets from another sender than the first decoded one: a second sensor on the
  // port, decoded as if it were the first (--filter "src host …" keeps one).
  std::uint64_t other_senders = 0;
  unsigned passes = 0;
  std::optional<std::string> read_error;  // the capture was damaged after this many frames
  bool empty_window = false;              // --start/--duration held no packet
  double capture_span_s = 0;              // of the whole capture, for the empty-window message
};

// Replays the capture into `target` until its end (or, with --loop, until stopped).
ReplayResult replay(const ReplayArgs& args, ReplayTarget& target, const apps::StopSignal& stop,
                    const std::string& tool);

}  // namespace sim::pcap
