// SPDX-License-Identifier: Apache-2.0
// sim_lidar_ouster: an Ouster OS0/OS1/OS2's lidar and IMU packets into SIM streams, one point
// frame per rotation. The work is the stream library's (sim/ouster/live_receiver.hpp: sockets,
// batched receive, silence; LidarStream: decode straight into shared memory, the path
// sim_replay_pcap takes too); this program is its command line, its messages and its exit code.
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/ouster_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/ouster/live_receiver.hpp"
#include "sim/ouster/metadata_client.hpp"

namespace {

constexpr char tool[] = "sim_lidar_ouster";

struct Options {
  sim::apps::OusterStreamOptions stream;
  std::string bind = "0.0.0.0";
  std::optional<int> lidar_port;  // nullopt: the metadata's udp_port_lidar
  std::optional<int> imu_port;
  std::string multicast_group;
  std::string source;
  int receive_buffer = 32 << 20;
  std::optional<double> status_interval;
  double silence_timeout = 0.5;
  bool metadata_from_sensor = false;
  std::string sensor_ip;
  int http_port = 80;
  double http_timeout = 5.0;
  bool summary = false;
  bool quiet = false;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  using sim::apps::validator;
  CLI::App& app = cli.app();
  cli.add_config_file({"calibration"});
  sim::apps::add_ouster_stream_options(cli, o.stream);
  const auto ipv4 = validator(sim::ouster::ipv4_problem, "ADDR");
  app.add_option("--bind", o.bind, "local IPv4 address to receive on")->type_name("ADDR")->check(ipv4);
  app.add_option("--lidar-port,--port", o.lidar_port, "UDP port of the lidar packets [the metadata's, 7502]; 0 picks a free one")
      ->check(CLI::Range(0, 65535));
  app.add_option("--imu-port", o.imu_port, "UDP port of the IMU packets [the metadata's, 7503]; 0 picks a free one")
      ->check(CLI::Range(0, 65535));
  app.add_option("--multicast,--multicast-group", o.multicast_group, "join this multicast group")
      ->type_name("GROUP")
      ->check(validator(sim::ouster::multicast_group_problem, "GROUP"));
  app.add_option("--source", o.source, "accept packets only from this sender address")->type_name("ADDR")->check(ipv4);
  app.add_option("--receive-buffer", o.receive_buffer, "SO_RCVBUF to ask for per socket, bytes")
      ->check(CLI::Range(65536, 1 << 30));
  app.add_option("--status-interval", o.status_interval,
                 "seconds between status lines; 0 for none [1 on a terminal, 10 otherwise]")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--silence-timeout", o.silence_timeout,
                 "a gap this long (s) means the sensor stopped: the next packet starts a new frame")
      ->check(CLI::PositiveNumber);
  app.add_flag("--metadata-from-sensor", o.metadata_from_sensor,
               "fetch the metadata from the sensor's HTTP API at start, check it and cache it in "
               "the --calibration file [~/.cache/sim/ouster-<ip>.json]; when the sensor does not "
               "deliver it, the cached file is used with a warning");
  app.add_option("--sensor-ip", o.sensor_ip, "the sensor's address for --metadata-from-sensor [--source]")
      ->type_name("IP")
      ->check(ipv4);
  app.add_option("--http-port", o.http_port, "the sensor's HTTP port")->check(CLI::Range(1, 65535));
  app.add_option("--http-timeout", o.http_timeout, "seconds the metadata download may take")
      ->check(CLI::Range(0.01, 60.0));
  app.add_flag("--summary", o.summary, "print one line of counters on exit: summary frames=… packets=…");
  app.add_flag("-q,--quiet", o.quiet, "no status line and no final line");
}

std::string sentence(std::string text) {
  while (!text.empty() && (text.back() == '.' || text.back() == ' ')) text.pop_back();
  return text + ".";
}

// The metadata: from the file, or from the sensor with the file as cache. An exit code on failure.
std::optional<int> load_metadata(const sim::apps::CommandLine& cli, Options& o, sim::apps::StatusLine& status,
                                 std::optional<sim::ouster::Metadata>& metadata, std::string& source) {
  if (!o.metadata_from_sensor) {
    auto loaded = sim::ouster::Metadata::load(o.stream.calibration);
    if (!loaded) return cli.fail(sentence(loaded.error().message));
    metadata = std::move(loaded.value());
    source = "file://" + std::filesystem::absolute(o.stream.calibration).string();
    return std::nullopt;
  }
  sim::ouster::HttpEndpoint sensor;
  sensor.host = !o.sensor_ip.empty() ? o.sensor_ip : o.source;
  if (sensor.host.empty()) {
    return cli.usage_error("--metadata-from-sensor needs the sensor's address: give --sensor-ip (or --source)");
  }
  sensor.port = static_cast<std::uint16_t>(o.http_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.http_timeout * 1000));
  if (o.stream.calibration.empty()) o.stream.calibration = sim::ouster::default_metadata_cache(sensor.host).string();
  auto fetched = sim::ouster::metadata_from_sensor(sensor, o.stream.calibration);
  if (!fetched) return cli.fail(sentence(fetched.error().message));
  if (fetched->from_cache) {
    status.note("warning: " + sentence(fetched->warning));
    source = "file://" + std::filesystem::absolute(o.stream.calibration).string();
  } else {
    std::printf("%s: metadata of sensor %s fetched and cached in %s\n", tool, sensor.host.c_str(),
                o.stream.calibration.c_str());
    std::fflush(stdout);
    source = "sensor http://" + sensor.host + "/api/v1/sensor/metadata";
  }
  metadata = std::move(fetched->metadata);
  return std::nullopt;
}

std::string status_text(const sim::ouster::LiveReceiver& receiver, const sim::ouster::LidarStream& stream,
                        const std::string& name, std::int64_t silence_ns, bool final_line) {
  std::string line = name + " " + stream.metadata().prod_line + ": " + stream.describe_counters();
  const auto& c = receiver.counters();
  if (c.other_source != 0) line += " other-source " + std::to_string(c.other_source);
  if (c.oversized != 0) line += " oversized " + std::to_string(c.oversized);
  const std::int64_t last = receiver.last_packet_ns();
  if (!final_line && last == 0) line += "  (no packets yet)";
  if (!final_line && last != 0 && sim::monotonic_ns() - last > silence_ns) {
    line += "  (no packets for " + std::to_string((sim::monotonic_ns() - last) / 1'000'000'000) + " s)";
  }
  return line;
}

int run(const sim::apps::CommandLine& cli, Options& o) {
  const auto& stop = sim::apps::StopSignal::install();
  auto status = sim::apps::StatusLine::for_stderr(tool, o.quiet);
  auto config = sim::apps::ouster_stream_config(o.stream);
  if (!config) return cli.fail(config.error());
  std::optional<sim::ouster::Metadata> metadata;
  if (auto code = load_metadata(cli, o, status, metadata, config->metadata_source)) return *code;

  sim::ouster::NetworkConfig network;
  network.bind = o.bind;
  network.lidar_port = static_cast<std::uint16_t>(o.lidar_port.value_or(metadata->udp_port_lidar));
  network.imu_port = static_cast<std::uint16_t>(o.imu_port.value_or(metadata->udp_port_imu));
  network.multicast_group = o.multicast_group;
  network.source = o.source;
  network.receive_buffer = o.receive_buffer;
  network.silence_timeout = std::chrono::nanoseconds(static_cast<std::int64_t>(o.silence_timeout * 1e9));
  auto receiver = sim::ouster::LiveReceiver::open(network);
  if (!receiver) return cli.fail(std::string_view(receiver.error().message));
  std::printf("%s: listening on %s lidar port %u imu port %u for %s\n", tool, o.bind.c_str(),
              receiver->lidar_port(), receiver->imu_port(), metadata->describe().c_str());
  std::fflush(stdout);
  if (receiver->receive_buffer() < network.receive_buffer) {
    status.note("the receive buffer is " + std::to_string(receiver->receive_buffer()) +
                " bytes, less than the " + std::to_string(network.receive_buffer) +
                " asked; raise it with sysctl -w net.core.rmem_max=" + std::to_string(network.receive_buffer) +
                " to ride out stalls without losing packets.");
  }
  config->heartbeat_period = std::chrono::milliseconds(500);
  auto stream = sim::ouster::LidarStream::create(*config, *metadata);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;

  const bool live = sim::apps::stderr_is_terminal() && !o.quiet;
  const double interval = o.status_interval.value_or(live ? 1.0 : 10.0);
  const std::int64_t silence_ns = network.silence_timeout.count();
  sim::ouster::ReceiverCallbacks callbacks;
  callbacks.note = [&](std::string_view message) { status.note(sentence(std::string(message))); };
  if (interval > 0 && !o.quiet) {
    callbacks.tick_period = std::chrono::nanoseconds(static_cast<std::int64_t>(interval * 1e9));
    callbacks.tick = [&] {
      const std::string text = status_text(*receiver, *stream, o.stream.stream, silence_ns, false);
      if (live) {
        status.update(text);
      } else {
        status.note(text);
      }
    };
  }
  receiver->run(*stream, stop.fd(), callbacks);
  status.finish(status_text(*receiver, *stream, o.stream.stream, silence_ns, true));
  if (o.summary) {
    const auto& c = receiver->counters();
    std::printf("summary %s datagrams=%llu other_source=%llu oversized=%llu resumes=%llu\n",
                stream->describe_counters(true).c_str(), static_cast<unsigned long long>(c.datagrams),
                static_cast<unsigned long long>(c.other_source), static_cast<unsigned long long>(c.oversized),
                static_cast<unsigned long long>(c.resumes));
    std::fflush(stdout);
  }
  return sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      tool,
      "Receives an Ouster OS0/OS1/OS2's lidar and IMU packets and publishes one SIM frame per "
      "rotation (points in the sensor frame, decoded straight into shared memory) and one per "
      "IMU sample. Settings come from --config and/or the options below (options win).");
  Options o;
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (o.stream.calibration.empty() && !o.metadata_from_sensor) {
    return cli.usage_error(
        "no metadata given; pass the sensor's metadata JSON with --calibration (save what "
        "http://SENSOR/api/v1/sensor/metadata returns), or use --metadata-from-sensor");
  }
  return run(cli, o);
}
