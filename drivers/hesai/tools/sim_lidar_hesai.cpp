// SPDX-License-Identifier: Apache-2.0
// sim_lidar_hesai: a Hesai Pandar's UDP packets into a SIM stream, one frame per revolution.
// The work is the stream library's (sim/hesai/live_receiver.hpp: socket, batched receive, model
// detection, silence; LidarStream: decode straight into shared memory, the path sim_replay_pcap
// takes too); this program is its command line, its messages and its exit code.
#include <arpa/inet.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/hesai_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/hesai/live_receiver.hpp"
#include "sim/hesai/ptc_client.hpp"

namespace {

constexpr char tool[] = "sim_lidar_hesai";

struct NetworkOptions {
  std::string bind = "0.0.0.0";
  int port = 2368;
  std::string multicast_group;
  std::string source;
  int receive_buffer = 16 << 20;
  std::optional<double> status_interval;  // nullopt: 1 s on a terminal, 10 s otherwise
  double silence_timeout = 0.5;
};

struct SensorOptions {
  bool calibration_from_sensor = false;
  std::string sensor_ip;  // empty: --source, else Hesai's factory address
  int ptc_port = sim::hesai::ptc::default_port;
  double ptc_timeout = 3.0;
};

struct Options {
  sim::apps::HesaiStreamOptions stream;
  NetworkOptions network;
  SensorOptions sensor;
  bool summary = false;
  bool quiet = false;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  using sim::apps::validator;
  CLI::App& app = cli.app();
  // Relative file names in a config file are taken relative to the file's folder.
  cli.add_config_file({"calibration", "firetimes"});
  sim::apps::add_hesai_stream_options(cli, o.stream);
  const auto address = validator(sim::hesai::address_problem, "ADDR");
  app.add_option("--bind", o.network.bind, "local address to receive on")
      ->type_name("ADDR")
      ->check(address);
  app.add_option("--port", o.network.port, "UDP port the sensor sends to; 0 picks a free one")
      ->check(CLI::Range(0, 65535));
  app.add_option("--multicast,--multicast-group", o.network.multicast_group,
                 "join this multicast group")
      ->type_name("GROUP")
      ->check(validator(sim::hesai::multicast_group_problem, "GROUP"));
  app.add_option("--source", o.network.source, "accept packets only from this sender address")
      ->type_name("ADDR")
      ->check(address);
  app.add_option("--receive-buffer", o.network.receive_buffer, "SO_RCVBUF to ask for, bytes")
      ->check(CLI::Range(65536, 1 << 30));
  app.add_option("--status-interval", o.network.status_interval,
                 "seconds between status lines; 0 for none [1 on a terminal, 10 otherwise]")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--silence-timeout", o.network.silence_timeout,
                 "a gap this long (s) means the sensor stopped: the next packet starts a new frame")
      ->check(CLI::PositiveNumber);
  app.add_flag("--calibration-from-sensor", o.sensor.calibration_from_sensor,
               "fetch the unit's angle-correction file from the sensor over PTC (TCP) at start, "
               "check it and cache it in the --calibration file [~/.cache/sim/hesai-<ip>.csv]; "
               "when the sensor does not deliver it, the cached file is used with a warning");
  app.add_option("--sensor-ip", o.sensor.sensor_ip,
                 "the sensor's address for --calibration-from-sensor [--source, else 192.168.1.201]")
      ->type_name("IP");
  app.add_option("--ptc-port", o.sensor.ptc_port, "the sensor's PTC port")->check(CLI::Range(1, 65535));
  app.add_option("--ptc-timeout", o.sensor.ptc_timeout,
                 "seconds the whole calibration download may take")
      ->check(CLI::Range(0.01, 60.0));
  app.add_flag("--summary", o.summary,
               "print one line of counters on exit: summary frames=… packets=… lost=… malformed=…");
  app.add_flag("-q,--quiet", o.quiet, "no status line and no final line");
}

// Messages joined from several parts end with exactly one full stop.
std::string sentence(std::string text) {
  while (!text.empty() && (text.back() == '.' || text.back() == ' ')) text.pop_back();
  return text + ".";
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
  } else if (!o.network.source.empty()) {
    sensor.host = o.network.source;
  }
  sensor.port = static_cast<std::uint16_t>(o.sensor.ptc_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.sensor.ptc_timeout * 1000));
  in_addr ignored{};
  if (inet_pton(AF_INET, sensor.host.c_str(), &ignored) != 1) {
    return cli.usage_error("--sensor-ip '" + sensor.host +
                           "' is not an IPv4 address (e.g. 192.168.1.201)");
  }
  if (o.stream.calibration.empty()) {
    o.stream.calibration = sim::hesai::default_calibration_cache(sensor.host).string();
  }
  auto fetched = sim::hesai::calibration_from_sensor(sensor, o.stream.calibration,
                                                     sim::apps::hesai_model(o.stream));
  if (!fetched) return cli.fail(sentence(fetched.error().message));
  if (fetched->from_cache) {
    status.note("warning: " + sentence(fetched->warning));
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
                sentence(identity.error().message));
  }
  return std::nullopt;
}

std::string status_text(const sim::hesai::LiveReceiver& receiver, const std::string& stream,
                        std::int64_t silence_ns, bool final_line) {
  std::string line;
  const sim::hesai::LidarStream* published = receiver.stream();
  if (published != nullptr) {
    line = stream + " " + std::string(sim::hesai::to_string(published->model())) + ": " +
           published->describe_counters();
  } else {
    line = "waiting for Hesai packets on port " + std::to_string(receiver.port());
  }
  const auto& counters = receiver.counters();
  if (counters.other_source != 0) line += " other-source " + std::to_string(counters.other_source);
  if (counters.unrecognised != 0) line += " unrecognised " + std::to_string(counters.unrecognised);
  const std::int64_t last = receiver.last_packet_ns();
  const std::int64_t now = sim::monotonic_ns();
  if (!final_line && last != 0 && now - last > silence_ns) {
    line += "  (no packets for " + std::to_string((now - last) / 1'000'000'000) + " s)";
  } else if (!final_line && last == 0 && published != nullptr) {
    line += "  (no packets yet)";
  }
  return line;
}

unsigned long long ull(std::uint64_t v) { return static_cast<unsigned long long>(v); }

int run(const sim::apps::CommandLine& cli, Options& o) {
  // Before any socket or stream exists: a stop request from here on ends the program cleanly.
  const auto& stop = sim::apps::StopSignal::install();
  auto status = sim::apps::StatusLine::for_stderr(tool, o.quiet);
  FromSensor from_sensor;
  if (o.sensor.calibration_from_sensor) {
    if (auto code = fetch_calibration(cli, o, status, from_sensor)) return *code;
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
  network.bind = o.network.bind;
  network.port = static_cast<std::uint16_t>(o.network.port);
  network.multicast_group = o.network.multicast_group;
  network.source = o.network.source;
  network.receive_buffer = o.network.receive_buffer;
  network.silence_timeout =
      std::chrono::nanoseconds(static_cast<std::int64_t>(o.network.silence_timeout * 1e9));
  auto receiver = sim::hesai::LiveReceiver::open(network);
  if (!receiver) return cli.fail(receiver.error());
  // On stdout, for scripts and tests that bind port 0.
  std::printf("%s: listening on %s\n", tool, receiver->local_address().c_str());
  std::fflush(stdout);
  if (receiver->receive_buffer() < network.receive_buffer) {
    status.note("the receive buffer is " + std::to_string(receiver->receive_buffer()) +
                " bytes, less than the " + std::to_string(network.receive_buffer) +
                " asked; raise it with sysctl -w net.core.rmem_max=" +
                std::to_string(network.receive_buffer) +
                " to ride out stalls without losing packets.");
  }

  config.heartbeat_period = std::chrono::milliseconds(500);
  if (auto published = receiver->publish_to(config, sim::apps::hesai_model(o.stream)); !published) {
    return cli.fail(std::string_view(published.error().message));
  }
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;

  const bool live = sim::apps::stderr_is_terminal() && !o.quiet;
  const double interval = o.network.status_interval.value_or(live ? 1.0 : 10.0);
  const std::int64_t silence_ns = network.silence_timeout.count();
  sim::hesai::ReceiverCallbacks callbacks;
  callbacks.note = [&](std::string_view message) { status.note(message); };
  if (interval > 0 && !o.quiet) {
    callbacks.tick_period = std::chrono::nanoseconds(static_cast<std::int64_t>(interval * 1e9));
    callbacks.tick = [&] {
      const std::string text = status_text(*receiver, o.stream.stream, silence_ns, false);
      // On a terminal the line is redrawn in place; in a log each tick is a line of its own.
      if (live) {
        status.update(text);
      } else {
        status.note(text);
      }
    };
  }
  if (auto ran = receiver->run(stop.fd(), callbacks); !ran) {
    return cli.fail(std::string_view(ran.error().message));
  }

  status.finish(status_text(*receiver, o.stream.stream, silence_ns, true));
  if (o.summary) {
    const sim::hesai::LidarStream* published = receiver->stream();
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
