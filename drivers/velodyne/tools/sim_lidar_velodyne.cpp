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
#include "sim/apps/live_lidar.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/apps/velodyne_options.hpp"
#include "sim/velodyne/live_receiver.hpp"

namespace {

constexpr char tool[] = "sim_lidar_velodyne";

struct Options {
  sim::apps::VelodyneStreamOptions stream;
  sim::apps::LiveReceiveOptions receive;
  int port = sim::velodyne::default_data_port;
  int position_port = sim::velodyne::default_position_port;
  bool no_position = false;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  cli.add_config_file({"calibration"});
  sim::apps::add_velodyne_stream_options(cli, o.stream);
  sim::apps::add_receive_options(cli, o.receive, sim::lidar::IpVersions::v4, [&o](sim::apps::CommandLine& ports) {
    ports.add_option("--port", o.port, "UDP port of the data packets; 0 picks a free one").in_range(0, 65535);
    ports.add_option("--position-port", o.position_port,
                     "UDP port of the position packets (GPRMC, PPS); 0 picks a free one")
        .in_range(0, 65535);
    ports.add_flag("--no-position", o.no_position, "do not listen for position packets");
  });
  sim::apps::add_output_options(cli, o.receive,
                                "print one line of counters on exit: summary frames=… packets=… lost=…");
}

int run(const sim::apps::CommandLine& cli, Options& o) {
  const auto& stop = sim::apps::StopSignal::install();
  sim::apps::LiveStatus status(tool, o.receive);
  // The options' problems (a bad --frame-id file…) before any socket exists.
  auto config = sim::apps::velodyne_stream_config(o.stream);
  if (!config) return cli.fail(config.error());
  config->heartbeat_period = std::chrono::milliseconds(500);

  sim::velodyne::NetworkConfig network;
  sim::apps::set_listen(network.listen, o.receive);
  network.data_port = static_cast<std::uint16_t>(o.port);
  network.position_port.reset();
  if (!o.no_position) network.position_port = static_cast<std::uint16_t>(o.position_port);
  auto receiver = sim::velodyne::LiveReceiver::open(network);
  if (!receiver) return cli.fail(receiver.error());
  // On stdout, for scripts and tests that bind port 0.
  std::printf("%s: listening on %s (position packets on port %u)\n", tool, receiver->local_address().c_str(),
              static_cast<unsigned>(receiver->position_port()));
  std::fflush(stdout);
  status.check_receive_buffer(receiver->receive_buffer(), network.listen.receive_buffer);
  if (auto published = receiver->publish_to(*config, sim::apps::velodyne_model(o.stream)); !published) {
    return cli.fail(std::string_view(published.error().message));
  }
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;
  const sim::apps::HostClockSource host_clock(o.receive);
  receiver->set_clock_sources(host_clock.sources());

  return sim::apps::run_model_receiver(
      cli, *receiver, status, stop.fd(),
      {"Velodyne", o.stream.stream, receiver->data_port(), network.listen.silence_timeout.count()});
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
