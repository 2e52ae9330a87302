// SPDX-License-Identifier: Apache-2.0
// sim_lidar_velodyne: a Velodyne's UDP packets into a SIM stream, one frame per revolution, and
// its position packets (GPRMC, PPS) into the stream's time-sync description. The work is the
// stream library's (sim/velodyne/live_receiver.hpp: sockets, batched receive, model detection,
// silence; LidarStream: decode straight into shared memory, the path sim_replay_pcap takes
// too); this program is its command line, its messages and its exit code.
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/apps/velodyne_options.hpp"
#include "sim/clock.hpp"
#include "sim/velodyne/live_receiver.hpp"

namespace {

constexpr char tool[] = "sim_lidar_velodyne";

struct Options {
  sim::apps::VelodyneStreamOptions stream;
  std::string bind = "0.0.0.0";
  int port = sim::velodyne::default_data_port;
  int position_port = sim::velodyne::default_position_port;
  bool no_position = false;
  std::string multicast_group;
  std::string source;
  int receive_buffer = 8 << 20;
  std::optional<double> status_interval;
  double silence_timeout = 0.5;
  bool summary = false;
  bool quiet = false;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  using sim::apps::validator;
  CLI::App& app = cli.app();
  cli.add_config_file({"calibration"});
  sim::apps::add_velodyne_stream_options(cli, o.stream);
  const auto ipv4 = validator(sim::velodyne::address_problem, "ADDR");
  app.add_option("--bind", o.bind, "local IPv4 address to receive on")->type_name("ADDR")->check(ipv4);
  app.add_option("--port", o.port, "UDP port of the data packets; 0 picks a free one")->check(CLI::Range(0, 65535));
  app.add_option("--position-port", o.position_port,
                 "UDP port of the position packets (GPRMC, PPS); 0 picks a free one")
      ->check(CLI::Range(0, 65535));
  app.add_flag("--no-position", o.no_position, "do not listen for position packets");
  app.add_option("--multicast,--multicast-group", o.multicast_group, "join this multicast group")
      ->type_name("GROUP")
      ->check(validator(sim::velodyne::multicast_group_problem, "GROUP"));
  app.add_option("--source", o.source, "accept packets only from this sender address")->type_name("ADDR")->check(ipv4);
  app.add_option("--receive-buffer", o.receive_buffer, "SO_RCVBUF to ask for, bytes")->check(CLI::Range(65536, 1 << 30));
  app.add_option("--status-interval", o.status_interval,
                 "seconds between status lines; 0 for none [1 on a terminal, 10 otherwise]")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--silence-timeout", o.silence_timeout,
                 "a gap this long (s) means the sensor stopped: the next packet starts a new frame")
      ->check(CLI::PositiveNumber);
  app.add_flag("--summary", o.summary, "print one line of counters on exit: summary frames=… packets=… lost=…");
  app.add_flag("-q,--quiet", o.quiet, "no status line and no final line");
}

std::string status_text(const sim::velodyne::LiveReceiver& receiver, const std::string& stream,
                        std::int64_t silence_ns, bool final_line) {
  std::string line;
  const sim::velodyne::LidarStream* published = receiver.stream();
  if (published != nullptr) {
    line = stream + " " + std::string(sim::velodyne::to_string(published->model())) + ": " +
           published->describe_counters();
  } else {
    line = "waiting for Velodyne packets on port " + std::to_string(receiver.data_port());
  }
  const auto& c = receiver.counters();
  if (c.other_source != 0) line += " other-source " + std::to_string(c.other_source);
  if (c.unrecognised != 0) line += " unrecognised " + std::to_string(c.unrecognised);
  const std::int64_t last = receiver.last_packet_ns();
  if (!final_line && last != 0 && sim::monotonic_ns() - last > silence_ns) {
    line += "  (no packets for " + std::to_string((sim::monotonic_ns() - last) / 1'000'000'000) + " s)";
  }
  return line;
}

unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }

int run(const sim::apps::CommandLine& cli, Options& o) {
  const auto& stop = sim::apps::StopSignal::install();
  auto status = sim::apps::StatusLine::for_stderr(tool, o.quiet);
  // The options' problems (a bad --frame-id file…) before any socket exists.
  auto config = sim::apps::velodyne_stream_config(o.stream);
  if (!config) return cli.fail(config.error());
  config->heartbeat_period = std::chrono::milliseconds(500);

  sim::velodyne::NetworkConfig network;
  network.bind = o.bind;
  network.data_port = static_cast<std::uint16_t>(o.port);
  if (!o.no_position) network.position_port = static_cast<std::uint16_t>(o.position_port);
  else network.position_port.reset();
  network.multicast_group = o.multicast_group;
  network.source = o.source;
  network.receive_buffer = o.receive_buffer;
  network.silence_timeout = std::chrono::nanoseconds(static_cast<std::int64_t>(o.silence_timeout * 1e9));
  auto receiver = sim::velodyne::LiveReceiver::open(network);
  if (!receiver) return cli.fail(receiver.error());
  // On stdout, for scripts and tests that bind port 0.
  std::printf("%s: listening on %s (position packets on port %u)\n", tool, receiver->local_address().c_str(),
              static_cast<unsigned>(receiver->position_port()));
  std::fflush(stdout);
  if (receiver->receive_buffer() < network.receive_buffer) {
    status.note("the receive buffer is " + std::to_string(receiver->receive_buffer()) + " bytes, less than the " +
                std::to_string(network.receive_buffer) + " asked; raise it with sysctl -w net.core.rmem_max=" +
                std::to_string(network.receive_buffer) + " to ride out stalls without losing packets.");
  }
  if (auto published = receiver->publish_to(*config, sim::apps::velodyne_model(o.stream)); !published) {
    return cli.fail(std::string_view(published.error().message));
  }
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;

  const bool live = sim::apps::stderr_is_terminal() && !o.quiet;
  const double interval = o.status_interval.value_or(live ? 1.0 : 10.0);
  const std::int64_t silence_ns = network.silence_timeout.count();
  sim::velodyne::ReceiverCallbacks callbacks;
  callbacks.note = [&](std::string_view message) { status.note(message); };
  if (interval > 0 && !o.quiet) {
    callbacks.tick_period = std::chrono::nanoseconds(static_cast<std::int64_t>(interval * 1e9));
    callbacks.tick = [&] {
      const std::string text = status_text(*receiver, o.stream.stream, silence_ns, false);
      if (live) {
        status.update(text);
      } else {
        status.note(text);
      }
    };
  }
  if (auto ran = receiver->run(stop.fd(), callbacks); !ran) return cli.fail(std::string_view(ran.error().message));

  status.finish(status_text(*receiver, o.stream.stream, silence_ns, true));
  if (o.summary) {
    const sim::velodyne::LidarStream* published = receiver->stream();
    const auto& c = receiver->counters();
    std::printf("summary %s datagrams=%llu other_source=%llu unrecognised=%llu resumes=%llu\n",
                published != nullptr ? published->describe_counters(true).c_str()
                                     : "frames=0 packets=0 lost=0 malformed=0 wrong_model=0",
                ull(c.datagrams), ull(c.other_source), ull(c.unrecognised), ull(c.resumes));
    std::fflush(stdout);
  }
  return sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      tool,
      "Receives a Velodyne LiDAR's UDP packets (VLP-16, Puck, VLP-32C, HDL-32E, VLS-128, HDL-64E) and "
      "publishes one SIM frame per revolution (points decoded straight into shared memory); position "
      "packets give the stream's time-sync state. Settings come from --config and/or the options "
      "below (options win).");
  Options o;
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (o.stream.calibration.empty()) {
    return cli.usage_error(
        "no calibration file given; pass the sensor's YAML (nominal tables in /usr/share/sim/velodyne) or "
        "an HDL-64E's db.xml with --calibration, or in the --config file");
  }
  return run(cli, o);
}
