// SPDX-License-Identifier: Apache-2.0
// sim_lidar_unitree: a Unitree L1 or L2 LiDAR into SIM. The work is the stream library's
// (sim/unitree/live_receiver.hpp: lidar::UdpReceiver or the serial port; LidarStream: decode straight
// into shared memory, the path the replays take too); this program is its command line, its
// messages and its exit code.
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>

#include "sim/apps/command_line.hpp"
#include "sim/apps/host_clock_options.hpp"
#include "sim/apps/live_lidar.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/apps/unitree_options.hpp"
#include "sim/timing/host_clock.hpp"
#include "sim/unitree/lidar_stream.hpp"
#include "sim/unitree/live_receiver.hpp"

namespace {

constexpr char tool[] = "sim_lidar_unitree";

struct Options {
  sim::apps::UnitreeStreamOptions stream;
  sim::unitree::LiveSource source;
  bool udp_port_given = false;
  std::string record_path;
  bool summary = false;
  bool quiet = false;
  sim::timing::HostClockOptions host_clock;  // --ptp4l-socket
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  sim::apps::add_unitree_stream_options(cli, o.stream);
  cli.add_option("--udp-port,--bind-port", o.source.network.data_port,
                 "local UDP port the lidar sends to (0: any free port, printed on stdout)")
      .each([&o](const std::string&) { o.udp_port_given = true; });
  const auto address = [](const std::string& text) {
    return sim::lidar::address_problem(text, sim::lidar::IpVersions::v4_and_v6);
  };
  cli.add_option("--bind-address", o.source.network.bind, "local address to listen on").check(address);
  cli.add_option("--lidar-ip", o.source.network.source,
                 "accept datagrams only from this address (L2 factory default 192.168.1.62)")
      .check(address);
  cli.add_option("--serial", o.source.serial_device, "serial device instead of UDP");
  cli.add_option("--baud", o.source.baud, "serial baud rate (0: 2000000 for L1, 4000000 for L2)");
  cli.add_option("--record", o.record_path,
                 "also write every byte received, as received, to FILE (replay it with sim_replay_serial)");
  sim::apps::add_host_clock_options(cli, o.host_clock);
  cli.add_flag("--summary", o.summary,
               "print one line of counters on exit: summary frames=… packets=… lost=… malformed=… imu=…");
  cli.add_flag("-q,--quiet", o.quiet, "no status line");
}

// --record FILE, opened (truncated) when given.
sim::Expected<void> open_recording(const std::string& path, std::ofstream& record) {
  if (path.empty()) return {};
  record.open(path, std::ios::binary | std::ios::trunc);
  if (!record) {
    return sim::Error{sim::ErrorCode::system_error,
                      "cannot write the recording '" + path + "'; check the folder exists and is writable"};
  }
  return {};
}

int run(const sim::apps::CommandLine& cli, const Options& o) {
  const sim::unitree::Model model = sim::apps::unitree_model(o.stream);
  // An L1 needs a serial port (or a UDP port it sits behind): a usage error otherwise.
  if (model == sim::unitree::Model::l1 && o.source.serial_device.empty() && !o.udp_port_given) {
    return cli.usage_error(
        "the L1 speaks over a serial port: give --serial /dev/ttyUSB0, or --udp-port N when it sits behind "
        "a serial-to-UDP board");
  }
  auto config = sim::apps::unitree_stream_config(o.stream);  // checks the sensor options: exit 2
  if (!config) return cli.fail(config.error());
  // Before any port or stream is opened: a stop request ends the program cleanly from here on.
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;
  // The source first: a busy port or a missing device leaves no stream behind.
  auto receiver = sim::unitree::LiveReceiver::open(o.source, model);
  if (!receiver) return cli.fail(receiver.error());
  auto stream = sim::unitree::LidarStream::create(*config);
  if (!stream) return cli.fail(stream.error());
  std::ofstream record;
  if (auto opened = open_recording(o.record_path, record); !opened) return cli.fail(opened.error());

  // The host's synchronisation (ptp4l, the kernel), read on its own thread: the clock record
  // judges the stamps against it.
  sim::timing::HostClockWatchOptions watch_options;
  watch_options.clock = o.host_clock;
  if (o.quiet) watch_options.log = [](const std::string&) {};
  sim::timing::HostClockWatch host_clock(watch_options);
  sim::timing::ClockSources clock_sources;
  clock_sources.host = [&host_clock] { return host_clock.latest(); };
  stream->clock().set_sources(std::move(clock_sources));
  receiver->publish_to(*stream, record.is_open() ? &record : nullptr);

  // On stdout, for scripts and tests that bind port 0.
  std::printf("%s\n", receiver->where().c_str());
  std::fflush(stdout);
  auto status = sim::apps::StatusLine::for_stderr(tool, o.quiet);
  const auto status_text = [&] {
    std::string line = stream->describe_counters();
    if (receiver->other_senders() > 0) line += " other-senders " + std::to_string(receiver->other_senders());
    return line;
  };
  const auto tick = [&] { status.update(status_text()); };
  const auto note = [&](std::string_view sentence) { status.note(sim::apps::sentence(std::string(sentence))); };
  const auto ran = receiver->run(stop.fd(), tick, note);
  stream->finish();
  status.finish(status_text());
  if (o.summary) {
    std::printf("summary %s other_senders=%llu\n", stream->describe_counters(true).c_str(),
                static_cast<unsigned long long>(receiver->other_senders()));
    std::fflush(stdout);
  }
  if (!ran) return cli.fail(ran.error());
  return sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      tool,
      "Decode a Unitree L1 or L2 LiDAR into a SIM point stream (and its IMU into a second stream). L2: UDP "
      "(default port 6201) or --serial /dev/ttyACM0 (4,000,000 baud). L1: --serial /dev/ttyUSB0 (2,000,000 "
      "baud).");
  Options o;
  add_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  try {
    return run(cli, o);
  } catch (const std::exception& e) {
    return cli.fail(e.what());
  }
}
