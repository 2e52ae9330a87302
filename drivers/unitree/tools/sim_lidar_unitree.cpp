// SPDX-License-Identifier: Apache-2.0
// sim_lidar_unitree: a Unitree L1 or L2 LiDAR into SIM. Bytes come from UDP (L2's default, or
// an L1 behind its serial-to-UDP board) or a serial port (L1 always, L2 in serial work mode);
// whatever arrives goes through the same Decoder as the replay tools, straight into the
// stream's loaned slot.
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <array>
#include <functional>
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange

#include <boost/asio.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/host_clock_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/result.hpp"
#include "sim/timing/host_clock.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/sim_sink.hpp"

namespace asio = boost::asio;

namespace {

struct Options {
  std::string model_text;
  std::uint16_t udp_port = 6201;
  std::string bind_address = "0.0.0.0";
  std::string lidar_ip;
  std::string serial_device;
  unsigned baud = 0;
  std::string stream;
  std::string imu_stream;
  bool no_imu = false;
  std::uint32_t scan_packets = 18;
  bool sensor_time = false;
  float range_min = 0.0F;
  float range_max = 1.0e9F;
  std::string record_path;
  bool checksum = false;
  bool quiet = false;
  bool udp_port_given = false;
  sim::ThreadPlacement placement;
  sim::timing::HostClockOptions host_clock;  // --ptp4l-socket
  sim::apps::SensorOptions sensor;   // --frame-id, --parent-frame, --x … --yaw
  sim::SensorInfo sensor_info;       // what they describe, checked before anything is opened
};

// Everything read off the wire goes to the decoder, and to the recording when there is one.
class Pipeline {
 public:
  // Bytes flow only once the streams exist; the sources are opened before them so that a busy
  // port or a missing device leaves no stream behind.
  void attach(sim::unitree::UnitreeStream& stream, std::ofstream* record) {
    stream_ = &stream;
    record_ = record;
  }
  void on_bytes(std::span<const std::byte> bytes) {
    if (record_ != nullptr) {
      record_->write(reinterpret_cast<const char*>(bytes.data()),
                     static_cast<std::streamsize>(bytes.size()));
    }
    // The arrival of the bytes: the stamp of host-time scans, and what the L2's own clock is
    // measured against; the clock record is written about once a second.
    const std::int64_t arrival = sim::realtime_ns();
    stream_->push(bytes, arrival);
    stream_->tick_clock(arrival);
  }

 private:
  sim::unitree::UnitreeStream* stream_ = nullptr;
  std::ofstream* record_ = nullptr;
};

class UdpSource {
 public:
  UdpSource(asio::io_context& io, Pipeline& pipeline, std::optional<asio::ip::address> lidar)
      : socket_(io), pipeline_(pipeline), lidar_(lidar) {}

  void open(const asio::ip::udp::endpoint& local) {
    socket_.open(local.protocol());
    // No SO_REUSEADDR: a second listener on the port must fail loudly, not steal datagrams.
    // Bursts of 1044-B packets at ~64,000 points/s: a large kernel buffer rides out scheduling.
    boost::system::error_code ignored;
    socket_.set_option(asio::socket_base::receive_buffer_size(4 << 20), ignored);
    socket_.bind(local);
  }
  std::uint16_t port() const { return socket_.local_endpoint().port(); }
  std::uint64_t ignored_datagrams() const { return ignored_; }

  void start() {
    socket_.async_receive_from(asio::buffer(buffer_), sender_,
                               [this](const boost::system::error_code& ec, std::size_t n) {
                                 if (ec == asio::error::operation_aborted) return;
                                 if (!ec) {
                                   if (lidar_ && sender_.address() != *lidar_) {
                                     ++ignored_;
                                   } else {
                                     pipeline_.on_bytes(std::span(buffer_).first(n));
                                   }
                                 }
                                 start();
                               });
  }

 private:
  asio::ip::udp::socket socket_;
  Pipeline& pipeline_;
  std::optional<asio::ip::address> lidar_;
  asio::ip::udp::endpoint sender_;
  std::array<std::byte, 65536> buffer_{};
  std::uint64_t ignored_ = 0;
};

class SerialSource {
 public:
  SerialSource(asio::io_context& io, Pipeline& pipeline) : port_(io), pipeline_(pipeline) {}

  void open(const std::string& device, unsigned baud) {
    port_.open(device);
    port_.set_option(asio::serial_port_base::baud_rate(baud));
    port_.set_option(asio::serial_port_base::character_size(8));
    port_.set_option(asio::serial_port_base::parity(asio::serial_port_base::parity::none));
    port_.set_option(asio::serial_port_base::stop_bits(asio::serial_port_base::stop_bits::one));
    port_.set_option(
        asio::serial_port_base::flow_control(asio::serial_port_base::flow_control::none));
  }

  // `on_error` runs once when the device fails (unplugged, closed by the other side).
  template <typename OnError>
  void start(OnError on_error) {
    port_.async_read_some(asio::buffer(buffer_),
                          [this, on_error](const boost::system::error_code& ec, std::size_t n) {
                            if (ec == asio::error::operation_aborted) return;
                            if (n > 0) pipeline_.on_bytes(std::span(buffer_).first(n));
                            if (ec) {
                              on_error(ec);
                              return;
                            }
                            start(on_error);
                          });
  }

 private:
  asio::serial_port port_;
  Pipeline& pipeline_;
  std::array<std::byte, 16384> buffer_{};
};

// --lidar-ip and --bind-address as addresses.
struct Addresses {
  std::optional<asio::ip::address> lidar;  // none: datagrams from anyone
  asio::ip::address bind;
};

// The sources the options ask for, checked before anything is opened: an L1 needs a serial port
// (or a UDP port it sits behind), and the addresses must be addresses. A usage error otherwise.
sim::Expected<Addresses> check_sources(const Options& opt, sim::unitree::Model model) {
  const auto usage = [](std::string sentence) {
    return sim::Error{sim::ErrorCode::invalid_argument, std::move(sentence)};
  };
  if (model == sim::unitree::Model::l1 && opt.serial_device.empty() && !opt.udp_port_given) {
    return usage(
        "the L1 speaks over a serial port: give --serial /dev/ttyUSB0, or --udp-port N when it "
        "sits behind a serial-to-UDP board");
  }
  Addresses addresses;
  if (!opt.lidar_ip.empty()) {
    boost::system::error_code ec;
    addresses.lidar = asio::ip::make_address(opt.lidar_ip, ec);
    if (ec) {
      return usage("--lidar-ip '" + opt.lidar_ip +
                   "' is not an IP address; give one like 192.168.1.62");
    }
  }
  boost::system::error_code ec;
  addresses.bind = asio::ip::make_address(opt.bind_address, ec);
  if (ec) {
    return usage("--bind-address '" + opt.bind_address +
                 "' is not an IP address; give one like 0.0.0.0");
  }
  return addresses;
}

sim::unitree::UnitreeStreamOptions stream_options(const Options& opt, sim::unitree::Model model) {
  sim::unitree::DecoderOptions decoder_options;
  decoder_options.model = model;
  decoder_options.packets_per_scan = opt.scan_packets;
  decoder_options.time_source =
      opt.sensor_time ? sim::unitree::TimeSource::sensor : sim::unitree::TimeSource::host;
  decoder_options.range_min_m = opt.range_min;
  decoder_options.range_max_m = opt.range_max;

  sim::unitree::UnitreeStreamOptions options;
  options.decoder = decoder_options;
  options.points_stream = opt.stream;
  options.imu_stream = opt.imu_stream;
  options.no_imu = opt.no_imu;
  options.checksum = opt.checksum;
  options.sensor = opt.sensor_info;
  return options;
}

// Where the bytes come from: --serial, or else UDP.
struct Source {
  std::optional<UdpSource> udp;
  std::optional<SerialSource> serial;
  unsigned baud = 0;  // of the serial port
};

// Opens the source (before the streams exist: a busy port or a missing device leaves no stream
// behind); one sentence when it cannot.
sim::Expected<void> open_source(const Options& opt, const Addresses& addresses,
                                sim::unitree::Model model, asio::io_context& io,
                                Pipeline& pipeline, Source& source) {
  source.baud =
      opt.baud != 0 ? opt.baud : (model == sim::unitree::Model::l1 ? 2'000'000U : 4'000'000U);
  if (!opt.serial_device.empty()) {
    source.serial.emplace(io, pipeline);
    try {
      source.serial->open(opt.serial_device, source.baud);
    } catch (const boost::system::system_error& e) {
      return sim::Error{sim::ErrorCode::system_error,
                        "cannot open serial port " + opt.serial_device + " at " +
                            std::to_string(source.baud) + " baud (" + e.code().message() +
                            "); check the device path and that you may use it (group dialout)"};
    }
  } else {
    source.udp.emplace(io, pipeline, addresses.lidar);
    try {
      source.udp->open(asio::ip::udp::endpoint(addresses.bind, opt.udp_port));
    } catch (const boost::system::system_error& e) {
      return sim::Error{sim::ErrorCode::system_error,
                        "cannot listen on UDP " + opt.bind_address + ":" +
                            std::to_string(opt.udp_port) + " (" + e.code().message() +
                            "); pick a free port with --udp-port or stop the other listener"};
    }
  }
  return {};
}

// --record FILE, opened (truncated) when given.
sim::Expected<void> open_recording(const std::string& path, std::ofstream& record) {
  if (path.empty()) return {};
  record.open(path, std::ios::binary | std::ios::trunc);
  if (!record) {
    return sim::Error{sim::ErrorCode::system_error,
                      "cannot write the recording '" + path +
                          "'; check the folder exists and is writable"};
  }
  return {};
}

// Starts reading the source. A serial port that fails ends the run with exit code 1.
void start_reading(const Options& opt, const sim::apps::CommandLine& cli, asio::io_context& io,
                   Source& source, int& exit_code) {
  if (source.serial) {
    std::cout << "reading " << opt.serial_device << " at " << source.baud << " baud" << std::endl;
    source.serial->start([&](const boost::system::error_code& ec) {
      cli.fail("serial port " + opt.serial_device + " failed (" + ec.message() +
               "); check the cable and restart");
      exit_code = sim::apps::kExitFailure;
      io.stop();
    });
  } else {
    // Printed on stdout so scripts (and tests binding port 0) learn the port.
    std::cout << "listening on udp port " << source.udp->port() << std::endl;
    source.udp->start();
  }
}

// Runs the sources until a stop (or a failed serial port stops `io`), redrawing the status line,
// writing the clock record (also when packets stop coming) and flushing the recording once a
// second.
void run_until_stopped(asio::io_context& io, const sim::apps::StopSignal& stop,
                       sim::apps::StatusLine& status, const std::function<std::string()>& status_text,
                       sim::unitree::UnitreeStream& stream, std::ofstream& record) {
  // The stop signal's descriptor ends io.run() like any other event.
  asio::posix::stream_descriptor stop_events(io, ::dup(stop.fd()));
  stop_events.async_wait(asio::posix::stream_descriptor::wait_read,
                         [&](const boost::system::error_code& ec) {
                           if (!ec) io.stop();
                         });
  asio::steady_timer status_timer(io);
  std::function<void()> tick = [&] {
    status_timer.expires_after(std::chrono::seconds(1));
    status_timer.async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      status.update(status_text());
      stream.tick_clock(sim::realtime_ns());
      if (record.is_open()) record.flush();
      tick();
    });
  };
  tick();
  if (!stop.requested()) io.run();
}

int run(const Options& opt, const sim::apps::CommandLine& cli) {
  const sim::unitree::Model model = *sim::unitree::parse_model(opt.model_text);
  auto addresses = check_sources(opt, model);
  if (!addresses) return cli.fail(addresses.error());
  // Before any port or stream is opened: a stop request ends the program cleanly from here on.
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(opt.placement)) return *code;

  Pipeline pipeline;
  asio::io_context io;
  Source source;
  if (auto opened = open_source(opt, *addresses, model, io, pipeline, source); !opened) {
    return cli.fail(opened.error());
  }
  auto stream = sim::unitree::UnitreeStream::create(stream_options(opt, model));
  if (!stream) return cli.fail(stream.error());
  std::ofstream record;
  if (auto opened = open_recording(opt.record_path, record); !opened) {
    return cli.fail(opened.error());
  }
  // The host's synchronisation (ptp4l, the kernel), read on its own thread: the clock record
  // judges the stamps against it.
  sim::timing::HostClockWatchOptions watch_options;
  watch_options.clock = opt.host_clock;
  if (opt.quiet) watch_options.log = [](const std::string&) {};
  sim::timing::HostClockWatch host_clock(watch_options);
  sim::lidar::ClockSources clock_sources;
  clock_sources.host = [&host_clock] { return host_clock.latest(); };
  (*stream)->clock().set_sources(std::move(clock_sources));
  pipeline.attach(**stream, record.is_open() ? &record : nullptr);

  int exit_code = sim::apps::kExitOk;
  start_reading(opt, cli, io, source, exit_code);
  auto status = sim::apps::StatusLine::for_stderr("sim_lidar_unitree", opt.quiet);
  const std::function<std::string()> status_text = [&] {
    std::string line = (*stream)->status();
    if (source.udp && source.udp->ignored_datagrams() > 0) {
      line += "  other_senders " + std::to_string(source.udp->ignored_datagrams());
    }
    return line;
  };
  run_until_stopped(io, stop, status, status_text, **stream, record);
  (*stream)->finish();
  if (record.is_open()) record.flush();
  status.finish(status_text());
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  sim::apps::CommandLine cli(
      "sim_lidar_unitree",
      "Decode a Unitree L1 or L2 LiDAR into a SIM point stream (and its IMU into a second "
      "stream). L2: UDP (default port 6201) or --serial /dev/ttyACM0 (4,000,000 baud). "
      "L1: --serial /dev/ttyUSB0 (2,000,000 baud).");
  auto& app = cli.app();
  app.add_option("--model", opt.model_text, "L1 or L2")
      ->required()
      ->check(sim::apps::validator(sim::unitree::model_problem, "Unitree model"));
  auto* udp_port = app.add_option("--udp-port,--bind-port", opt.udp_port,
                                  "local UDP port the lidar sends to (0: any free port, printed "
                                  "on stdout)");
  app.add_option("--bind-address", opt.bind_address, "local address to listen on");
  app.add_option("--lidar-ip", opt.lidar_ip,
                 "accept datagrams only from this address (L2 factory default 192.168.1.62)");
  app.add_option("--serial", opt.serial_device, "serial device instead of UDP");
  app.add_option("--baud", opt.baud, "serial baud rate (0: 2000000 for L1, 4000000 for L2)");
  cli.add_stream("--stream", opt.stream, "SIM point stream, e.g. /lidar_top")->required();
  cli.add_stream("--imu-stream", opt.imu_stream, "SIM IMU stream (empty: <stream>.imu)");
  app.add_flag("--no-imu", opt.no_imu, "do not publish IMU samples");
  app.add_option("--scan-packets", opt.scan_packets,
                 "packets per published scan (the SDKs' cloud_scan_num)")
      ->check(CLI::Range(1U, 1000U));
  app.add_flag("--sensor-time", opt.sensor_time,
               "stamp frames with the L2's own clock instead of host receive time");
  app.add_option("--range-min", opt.range_min, "drop points nearer than this (m)");
  app.add_option("--range-max", opt.range_max, "drop points farther than this (m)");
  app.add_option("--record", opt.record_path,
                 "also write every byte received, as received, to FILE (replay it with "
                 "sim_replay_serial)");
  app.add_flag("--checksum", opt.checksum, "publish frames with an XXH3 checksum");
  app.add_flag("-q,--quiet", opt.quiet, "no status line and no summary");
  sim::apps::add_sensor_options(cli, opt.sensor, sim::apps::SensorKind::lidar);
  sim::apps::add_host_clock_options(cli, opt.host_clock);
  cli.add_placement(opt.placement);
  if (auto code = cli.parse(argc, argv)) return *code;
  opt.udp_port_given = udp_port->count() > 0;
  auto sensor = sim::apps::sensor_info_from(opt.sensor, opt.stream);
  if (!sensor) return cli.fail(sensor.error());
  opt.sensor_info = std::move(sensor.value());
  try {
    return run(opt, cli);
  } catch (const std::exception& e) {
    return cli.fail(e.what());
  }
}
