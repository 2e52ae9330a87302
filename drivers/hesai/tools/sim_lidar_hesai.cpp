// SPDX-License-Identifier: Apache-2.0
// sim_lidar_hesai: a Hesai Pandar's UDP packets into a SIM stream, one frame per revolution.
// The work is the stream library's (sim/hesai/live_receiver.hpp: socket, batched receive, model
// detection, silence; LidarStream: decode straight into shared memory, the path sim_replay_pcap
// takes too); this program is its command line, its messages and its exit code.
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "sim/apps/clock_poll.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/hesai_options.hpp"
#include "sim/apps/live_lidar.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/hesai/live_receiver.hpp"
#include "sim/hesai/ptc_client.hpp"
#include "sim/hesai/ptc_clock.hpp"
#include "sim/lidar/tcp_client.hpp"

namespace {

constexpr char tool[] = "sim_lidar_hesai";

struct SensorOptions {
  bool calibration_from_sensor = false;
  std::string sensor_ip;  // empty: --source, else Hesai's factory address
  int ptc_port = sim::hesai::ptc::default_port;
  double ptc_timeout = 3.0;
  double clock_poll_seconds = 1.0;  // 0: the sensor's clock is not asked about
};

struct Options {
  sim::apps::HesaiStreamOptions stream;
  sim::apps::LiveReceiveOptions receive{.receive_buffer = 16 << 20};
  int port = 2368;
  SensorOptions sensor;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  // Relative file names in a config file are taken relative to the file's folder.
  cli.add_config_file({"calibration", "firetimes"});
  sim::apps::add_hesai_stream_options(cli, o.stream);
  sim::apps::add_receive_options(cli, o.receive, sim::lidar::IpVersions::v4_and_v6, [&o](sim::apps::CommandLine& ports) {
    ports.add_option("--port", o.port, "UDP port the sensor sends to; 0 picks a free one").in_range(0, 65535);
  });
  cli.add_flag("--calibration-from-sensor", o.sensor.calibration_from_sensor,
               "fetch the unit's angle-correction file from the sensor over PTC (TCP) at start, "
               "check it and cache it in the --calibration file [~/.cache/sim/hesai-<ip>.csv]; "
               "when the sensor does not deliver it, the cached file is used with a warning");
  cli.add_option("--sensor-ip", o.sensor.sensor_ip,
                 "the sensor's address or name for --calibration-from-sensor and its clock [--source, "
                 "else 192.168.1.201]")
      .type_name("ADDR|NAME");
  cli.add_option("--ptc-port", o.sensor.ptc_port, "the sensor's PTC port").in_range(1, 65535);
  cli.add_option("--ptc-timeout", o.sensor.ptc_timeout,
                 "seconds the whole calibration download, or one reading of the sensor's clock, "
                 "may take")
      .in_range(0.01, 60.0);
  sim::apps::add_clock_poll_option(cli, o.sensor.clock_poll_seconds);
  sim::apps::add_output_options(
      cli, o.receive, "print one line of counters on exit: summary frames=… packets=… lost=… malformed=…");
}

// What PTC told about the unit, for the stream's description.
struct FromSensor {
  sim::SensorIdentity identity;
  std::string calibration_source;
};

// Fetches the calibration over PTC into the --calibration file (the cache), and the unit's
// identity (a warning when the sensor does not tell it); an exit code when the program must end.
std::optional<int> fetch_calibration(const sim::apps::CommandLine& cli, Options& o,
                                     sim::apps::StatusLine& status, FromSensor& from_sensor) {
  sim::hesai::PtcEndpoint sensor;
  if (!o.sensor.sensor_ip.empty()) {
    sensor.host = o.sensor.sensor_ip;
  } else if (!o.receive.source.empty()) {
    sensor.host = o.receive.source;
  }
  sensor.port = static_cast<std::uint16_t>(o.sensor.ptc_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.sensor.ptc_timeout * 1000));
  if (const std::string problem = sim::lidar::host_problem(sensor.host); !problem.empty()) {
    return cli.usage_error("--sensor-ip " + problem);  // a name resolves when connecting
  }
  if (o.stream.calibration.empty()) {
    o.stream.calibration = sim::hesai::default_calibration_cache(sensor.host).string();
  }
  auto fetched = sim::hesai::calibration_from_sensor(sensor, o.stream.calibration,
                                                     sim::apps::hesai_model(o.stream));
  if (!fetched) return cli.fail(sim::apps::sentence(fetched.error().message));
  if (fetched->from_cache) {
    status.note("warning: " + sim::apps::sentence(fetched->warning));
    return std::nullopt;  // the stream names the cached file as the calibration's source
  }
  std::printf("%s: calibration of sensor %s (%zu channels) fetched and cached in %s\n", tool,
              sensor.host.c_str(), fetched->channels, o.stream.calibration.c_str());
  std::fflush(stdout);
  from_sensor.calibration_source = "sensor " + sensor.host + " over PTC";
  auto identity = sim::hesai::fetch_identity(sensor);
  if (identity) {
    from_sensor.identity = std::move(identity.value());
  } else {
    status.note("warning: the stream will not carry the unit's serial number: " +
                sim::apps::sentence(identity.error().message));
  }
  return std::nullopt;
}

// The sensor's clock over PTC every --clock-poll-seconds, off the frame path, when its address
// is known (--sensor-ip or --source); nullptr when not asked.
std::unique_ptr<sim::apps::ClockPoll> poll_clock(const Options& o) {
  const std::string host = !o.sensor.sensor_ip.empty() ? o.sensor.sensor_ip : o.receive.source;
  if (o.sensor.clock_poll_seconds <= 0 || host.empty()) return nullptr;
  sim::hesai::PtcEndpoint sensor;
  sensor.host = host;
  sensor.port = static_cast<std::uint16_t>(o.sensor.ptc_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.sensor.ptc_timeout * 1000));
  const auto period = std::chrono::milliseconds(static_cast<long>(o.sensor.clock_poll_seconds * 1000));
  return std::make_unique<sim::apps::ClockPoll>(
      sim::hesai::PtcClockReader(sensor, sim::apps::hesai_model(o.stream)), period);
}

int run(const sim::apps::CommandLine& cli, Options& o) {
  // Before any socket or stream exists: a stop request from here on ends the program cleanly.
  const auto& stop = sim::apps::StopSignal::install();
  sim::apps::LiveStatus status(tool, o.receive);
  FromSensor from_sensor;
  if (o.sensor.calibration_from_sensor) {
    if (auto code = fetch_calibration(cli, o, status.line(), from_sensor)) return *code;
  }
  auto configured = sim::apps::hesai_stream_config(o.stream);
  if (!configured) return cli.fail(configured.error());
  sim::hesai::LidarStreamConfig config = std::move(configured.value());
  config.sensor->identity = from_sensor.identity;  // vendor and model come from the packets
  config.sensor->calibration_source = from_sensor.calibration_source;
  // The packets carry the sensor's clock (UTC fields); whether PTP or GPS sets it, they do not say.
  config.sensor->time_base = sim::TimeBase::unknown;
  config.sensor->time_sync = "the sensor's clock, from its packets; synchronisation not reported";

  sim::hesai::NetworkConfig network;
  sim::apps::set_listen(network.listen, o.receive);
  network.data_port = static_cast<std::uint16_t>(o.port);
  auto receiver = sim::hesai::LiveReceiver::open(network);
  if (!receiver) return cli.fail(receiver.error());
  // On stdout, for scripts and tests that bind port 0.
  std::printf("%s: listening on %s\n", tool, receiver->local_address().c_str());
  std::fflush(stdout);
  status.check_receive_buffer(receiver->receive_buffer(), network.listen.receive_buffer);

  config.heartbeat_period = std::chrono::milliseconds(500);
  if (auto published = receiver->publish_to(config, sim::apps::hesai_model(o.stream)); !published) {
    return cli.fail(std::string_view(published.error().message));
  }
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;
  const sim::apps::HostClockSource host_clock(o.receive);

  sim::apps::ModelReceiverWords words{"Hesai", o.stream.stream, receiver->data_port(),
                                      network.listen.silence_timeout.count()};
  const auto clock = poll_clock(o);
  // The stream's clock check: its packets against their arrival, with the host's clock and what
  // the sensor reports of its own.
  sim::timing::ClockSources sources = host_clock.sources();
  if (clock) sources.reported = [&clock] { return clock->latest(); };
  receiver->set_clock_sources(std::move(sources));
  if (clock) {
    words.clock_tick = [&clock, &status] {
      for (const auto& note : clock->take_notes()) status.line().note(sim::apps::sentence(note));
    };
  }
  return sim::apps::run_model_receiver(cli, *receiver, status, stop.fd(), words);
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      tool,
      "Receives a Hesai Pandar LiDAR's UDP packets and publishes one SIM frame per revolution "
      "(points decoded straight into shared memory). Settings come from --config and/or the "
      "options below (options win).");
  Options o;
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (o.stream.calibration.empty() && !o.sensor.calibration_from_sensor) {
    return cli.usage_error(
        "no calibration file given; pass the sensor's angle-correction CSV with --calibration "
        "or in the --config file (every unit has its own), or use --calibration-from-sensor");
  }
  return run(cli, o);
}
