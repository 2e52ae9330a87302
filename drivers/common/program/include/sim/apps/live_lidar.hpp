// SPDX-License-Identifier: Apache-2.0
// What the three live LiDAR programs (sim_lidar_hesai, sim_lidar_velodyne, sim_lidar_ouster)
// share on the command line, so each is only its family's options and messages:
//
//   LiveReceiveOptions receive;  receive.receive_buffer = 16 << 20;      // the family's default
//   add_receive_options(cli, receive, IpVersions::v4, [&](CommandLine& ports) { …its --port… });
//   … the family's own options …
//   add_output_options(cli, receive, "print one line of counters on exit: …");
//   set_network(network, receive);                                       // its NetworkConfig
//   LiveStatus status(tool, receive);
//   receiver->run(stop.fd(), status.callbacks(text));  status.finish(summary, counters);
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "sim/apps/command_line.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/timing/host_clock.hpp"

namespace sim::apps {

struct LiveReceiveOptions {
  std::string bind = "0.0.0.0";
  std::string multicast_group{};
  std::string source{};
  int receive_buffer = 8 << 20;           // per socket, bytes
  std::optional<double> status_interval{};  // nullopt: 1 s on a terminal, 10 s otherwise
  double silence_timeout = 0.5;           // s
  bool summary = false;
  bool quiet = false;
  timing::HostClockOptions host_clock{};  // --ptp4l-socket: the host's clock for the clock check
  std::string stamp_fallback = "off";     // --stamp-fallback: "off" or "host" (timing::StampFallback)
};

// Adds --bind, the family's port options (`add_ports`), then --multicast, --source,
// --receive-buffer, --status-interval, --silence-timeout, --ptp4l-socket and --stamp-fallback;
// addresses are checked as `versions`.
void add_receive_options(CommandLine& cli, LiveReceiveOptions& options, lidar::IpVersions versions,
                         const std::function<void(CommandLine&)>& add_ports);
// Adds --summary (with `summary_help`) and -q,--quiet: the last options of each live program.
void add_output_options(CommandLine& cli, LiveReceiveOptions& options, const std::string& summary_help);

// The receiver's side of the options: bind, multicast group, source, receive buffer and
// silence timeout (the family keeps its IP versions).
void set_listen(lidar::UdpListen& listen, const LiveReceiveOptions& options);

// The host's clock for the stream's clock check, read once a second on its own thread (each
// change logged once on stderr, unless --quiet). Outlives the receiver's run().
class HostClockSource {
 public:
  explicit HostClockSource(const LiveReceiveOptions& options);
  // sources.host: the watch's last reading (never waits); the --stamp-fallback asked for.
  timing::ClockSources sources() const;

 private:
  timing::HostClockWatch watch_;
  timing::StampFallback stamp_fallback_;
};

// Adds --clock-poll-seconds: how often the sensor's clock is asked about (its PTC or HTTP
// service, off the frame path); 0 turns the asking off.
void add_clock_poll_option(CommandLine& cli, double& seconds);

// `callbacks` with `clock_tick` also called every `period` on the receive thread (before the
// status tick when both are due), for what must happen there: the clock's notes on the status
// line, a stamp correction the stream applies. An empty clock_tick leaves callbacks as they are.
lidar::ReceiverCallbacks with_clock_tick(lidar::ReceiverCallbacks callbacks, std::function<void()> clock_tick,
                                         std::chrono::nanoseconds period);

// Messages joined from several parts end with exactly one full stop.
std::string sentence(std::string text);

// What a status line adds after the stream's counters: the receive problems (" other-source 3")
// and, unless `final_line`, "  (no packets for 3 s)" when the last packet (CLOCK_MONOTONIC, 0:
// none yet) is older than `silence_ns`, or "  (no packets yet)" when none came and `expecting`
// (the stream exists).
std::string receive_status(const lidar::ReceiveCounters& counters, std::int64_t last_packet_ns,
                           std::int64_t silence_ns, bool expecting, bool final_line);

// The status side of a live program: notes, the status line every --status-interval (redrawn
// in place on a terminal, a line of its own in a log), the final line and the --summary.
class LiveStatus {
 public:
  // The status line's text; final_line: for the last line, when the program ends.
  using Text = std::function<std::string(bool final_line)>;

  LiveStatus(std::string tool, const LiveReceiveOptions& options);
  LiveStatus(const LiveStatus&) = delete;  // the callbacks point at it
  LiveStatus& operator=(const LiveStatus&) = delete;

  StatusLine& line() noexcept { return line_; }
  // A note when the kernel granted less receive buffer than asked, with the sysctl that helps.
  void check_receive_buffer(int granted, int asked);
  // The receiver's callbacks: its notes as sentences, and `text` every interval (unless quiet).
  lidar::ReceiverCallbacks callbacks(Text text);
  // The final line and, with --summary, on stdout: "summary <stream_summary> datagrams=…
  // other_source=… unrecognised=… oversized=… resumes=… other_senders=…".
  void finish(const std::string& stream_summary, const lidar::ReceiveCounters& counters);

 private:
  const LiveReceiveOptions& options_;
  bool live_;  // redraw in place: stderr is a terminal and not --quiet
  StatusLine line_;
  Text text_;
};

// How the status line names a receiver whose model the packets tell (Hesai, Velodyne):
// "/lidar_top Pandar64: frames 12 packets 3600 …", or "waiting for Hesai packets on port 2368"
// before the model is known.
struct ModelReceiverWords {
  std::string family;  // "Hesai"
  std::string stream;  // "/lidar_top"
  std::uint16_t port = 0;
  std::int64_t silence_ns = 0;  // the silence timeout
  std::function<void()> clock_tick{};  // once a second on the receive thread (with_clock_tick)
};

// Runs such a receiver (sim::hesai or sim::velodyne LiveReceiver) until `stop_fd` is readable,
// with the status line every interval, then the final line and the --summary. The program's exit
// code: 0, or 1 when the stream for a detected model could not be created.
template <class Receiver>
int run_model_receiver(const CommandLine& cli, Receiver& receiver, LiveStatus& status, int stop_fd,
                       const ModelReceiverWords& words) {
  const auto text = [&](bool final_line) {
    const auto* published = receiver.stream();
    std::string line = published != nullptr
                           ? words.stream + " " + std::string(to_string(published->model())) + ": " +
                                 published->describe_counters()
                           : "waiting for " + words.family + " packets on port " + std::to_string(words.port);
    return line + receive_status(receiver.counters(), receiver.last_packet_ns(), words.silence_ns,
                                 published != nullptr, final_line);
  };
  auto callbacks = with_clock_tick(status.callbacks(text), words.clock_tick, std::chrono::seconds(1));
  if (auto ran = receiver.run(stop_fd, std::move(callbacks)); !ran) return cli.fail(std::string_view(ran.error().message));
  const auto* published = receiver.stream();
  status.finish(published != nullptr ? published->describe_counters(true)
                                     : "frames=0 packets=0 lost=0 malformed=0 wrong_model=0",
                receiver.counters());
  return kExitOk;
}

}  // namespace sim::apps
