// SPDX-License-Identifier: Apache-2.0
// sim_lidar_ouster: an Ouster OS0/OS1/OS2's lidar and IMU packets into SIM streams, one point
// frame per rotation. The work is the stream library's (sim/ouster/live_receiver.hpp: sockets,
// batched receive, silence; LidarStream: decode straight into shared memory, the path
// sim_replay_pcap takes too); this program is its command line, its messages and its exit code.
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include "sim/apps/clock_poll.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/live_lidar.hpp"
#include "sim/apps/ouster_options.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/lidar/frame_publisher.hpp"
#include "sim/lidar/tcp_client.hpp"
#include "sim/ouster/live_receiver.hpp"
#include "sim/ouster/metadata_client.hpp"
#include "sim/ouster/time_client.hpp"

namespace {

constexpr char tool[] = "sim_lidar_ouster";

struct Options {
  sim::apps::OusterStreamOptions stream;
  sim::apps::LiveReceiveOptions receive{.receive_buffer = 32 << 20};
  std::optional<int> lidar_port;  // nullopt: the metadata's udp_port_lidar
  std::optional<int> imu_port;
  bool metadata_from_sensor = false;
  std::string sensor_ip;
  int http_port = 80;
  double http_timeout = 5.0;
  double clock_poll_seconds = 1.0;  // 0: the sensor's clock is not asked about
  std::string tai_correction;       // "", "auto" or seconds
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  cli.add_config_file({"calibration"});
  sim::apps::add_ouster_stream_options(cli, o.stream);
  sim::apps::add_receive_options(cli, o.receive, sim::lidar::IpVersions::v4, [&o](sim::apps::CommandLine& ports) {
    ports.add_option("--lidar-port,--port", o.lidar_port,
                     "UDP port of the lidar packets [the metadata's, 7502]; 0 picks a free one")
        .in_range(0, 65535);
    ports.add_option("--imu-port", o.imu_port, "UDP port of the IMU packets [the metadata's, 7503]; 0 picks a free one")
        .in_range(0, 65535);
  });
  cli.add_flag("--metadata-from-sensor", o.metadata_from_sensor,
               "fetch the metadata from the sensor's HTTP API at start, check it and cache it in "
               "the --calibration file [~/.cache/sim/ouster-<ip>.json]; when the sensor does not "
               "deliver it, the cached file is used with a warning");
  cli.add_option("--sensor-ip", o.sensor_ip,
                 "the sensor's address or name (os-122.local) for --metadata-from-sensor [--source]")
      .type_name("ADDR|NAME")
      .check(sim::lidar::host_problem);  // a name resolves at connect
  cli.add_option("--http-port", o.http_port, "the sensor's HTTP port").in_range(1, 65535);
  cli.add_option("--http-timeout", o.http_timeout,
                 "seconds the metadata download, or one reading of the sensor's clock, may take")
      .in_range(0.01, 60.0);
  sim::apps::add_clock_poll_option(cli, o.clock_poll_seconds);
  cli.add_option("--tai-correction", o.tai_correction,
                 "subtract TAI - UTC from the sensor's stamps (a PTP master serving TAI): 'auto' "
                 "takes the sensor's current_utc_offset while it reports the PTP timescale with a "
                 "valid offset (needs the clock asked about), or give the seconds (37); the "
                 "stream's clock record says it was done")
      .type_name("auto|SECONDS")
      .check([](const std::string& v) -> std::string {
        if (v == "auto") return {};
        try {
          std::size_t used = 0;
          const double seconds = std::stod(v, &used);
          if (used == v.size() && seconds >= -1000 && seconds <= 1000) return {};
        } catch (...) {
        }
        return "'" + v + "' is neither auto nor seconds between -1000 and 1000 (37 for TAI today)";
      });
  sim::apps::add_output_options(cli, o.receive, "print one line of counters on exit: summary frames=… packets=…");
}

// The metadata: from the file, or from the sensor with the file as cache. An exit code on failure.
std::optional<int> load_metadata(const sim::apps::CommandLine& cli, Options& o, sim::apps::StatusLine& status,
                                 std::optional<sim::ouster::Metadata>& metadata, std::string& source) {
  if (!o.metadata_from_sensor) {
    auto loaded = sim::ouster::Metadata::load(o.stream.calibration);
    if (!loaded) return cli.fail(sim::apps::sentence(loaded.error().message));
    metadata = std::move(loaded.value());
    source = sim::lidar::file_source(o.stream.calibration);
    return std::nullopt;
  }
  sim::ouster::HttpEndpoint sensor;
  sensor.host = !o.sensor_ip.empty() ? o.sensor_ip : o.receive.source;
  if (sensor.host.empty()) {
    return cli.usage_error("--metadata-from-sensor needs the sensor's address: give --sensor-ip (or --source)");
  }
  sensor.port = static_cast<std::uint16_t>(o.http_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.http_timeout * 1000));
  if (o.stream.calibration.empty()) o.stream.calibration = sim::ouster::default_metadata_cache(sensor.host).string();
  auto fetched = sim::ouster::metadata_from_sensor(sensor, o.stream.calibration);
  if (!fetched) return cli.fail(sim::apps::sentence(fetched.error().message));
  if (fetched->from_cache) {
    status.note("warning: " + sim::apps::sentence(fetched->warning));
    source = sim::lidar::file_source(o.stream.calibration);
  } else {
    std::printf("%s: metadata of sensor %s fetched and cached in %s\n", tool, sensor.host.c_str(),
                o.stream.calibration.c_str());
    std::fflush(stdout);
    source = "sensor http://" + sensor.host + "/api/v1/sensor/metadata";
  }
  metadata = std::move(fetched->metadata);
  return std::nullopt;
}

// The sensor's clock over HTTP every --clock-poll-seconds, off the frame path, when its address
// is known (--sensor-ip or --source); nullptr when not asked.
std::unique_ptr<sim::apps::ClockPoll> poll_clock(const Options& o) {
  const std::string host = !o.sensor_ip.empty() ? o.sensor_ip : o.receive.source;
  if (o.clock_poll_seconds <= 0 || host.empty()) return nullptr;
  sim::ouster::HttpEndpoint sensor;
  sensor.host = host;
  sensor.port = static_cast<std::uint16_t>(o.http_port);
  sensor.timeout = std::chrono::milliseconds(static_cast<long>(o.http_timeout * 1000));
  const auto period = std::chrono::milliseconds(static_cast<long>(o.clock_poll_seconds * 1000));
  return std::make_unique<sim::apps::ClockPoll>(sim::ouster::HttpClockReader(sensor), period);
}

// --tai-correction: what is subtracted from the stamps now (ns), applied on the receive thread,
// read by the clock report from any thread.
struct TaiCorrection {
  bool automatic = false;
  std::atomic<std::int64_t> applied_ns{0};

  // With `auto`: the correction the latest clock report calls for; nullopt to keep the current
  // one (no fresh report, or PTP timescale without a valid offset).
  static std::optional<std::int64_t> wanted(const sim::ClockStatus& clock) {
    if (clock.reported_ns == 0 || clock.source != sim::ClockSource::ptp) return std::nullopt;
    if (!clock.ptp_timescale) return 0;  // the master serves UTC: nothing to correct
    if (!clock.utc_offset_s) return std::nullopt;
    return std::int64_t{*clock.utc_offset_s} * 1'000'000'000;
  }
};

// The clock record's reported half: the sensor's report and what the driver does to its stamps.
sim::ClockStatus reported_clock(const sim::apps::ClockPoll* poll, const TaiCorrection& tai) {
  sim::ClockStatus clock = poll != nullptr ? poll->latest() : sim::ClockStatus{};
  clock.tai_correction_ns = tai.applied_ns.load(std::memory_order_relaxed);
  clock.stamps = clock.tai_correction_ns != 0 ? sim::StampClock::sensor_tai_corrected : sim::StampClock::sensor;
  return clock;
}

// --metadata-from-sensor: a sensor reconfigured from its web page (another lidar_mode) or
// restarted sends packets of a new initialization id, which the metadata in use refuses (the
// stream says so once). When for reconfigure_after_ns every lidar packet was refused so and none
// decoded, the session ends and the metadata is fetched again (review turn 4, L6).
constexpr std::int64_t reconfigure_after_ns = 2'000'000'000;

class ReconfigurationWatch {
 public:
  // About once a second, on the receive thread: true once the sensor has sent only packets of
  // another initialization id for reconfigure_after_ns.
  bool due(const sim::ouster::AssemblerCounters& c, std::int64_t now_ns) noexcept {
    const std::uint64_t refused = c.rejected[static_cast<unsigned>(sim::ouster::PacketError::init_id_mismatch)];
    const bool only_refused = refused > refused_ && c.packets == decoded_;
    refused_ = refused;
    decoded_ = c.packets;
    if (!only_refused) {
      since_ns_ = -1;
      return false;
    }
    if (since_ns_ < 0) since_ns_ = now_ns;
    return now_ns - since_ns_ >= reconfigure_after_ns;
  }

 private:
  std::uint64_t refused_ = 0;
  std::uint64_t decoded_ = 0;
  std::int64_t since_ns_ = -1;
};

// What ends one session's receive loop: a stop request (SIGINT/SIGTERM), or new metadata being
// needed. The receiver polls one descriptor, so it gets an epoll set of the stop eventfd and this
// session's own; without one (epoll unavailable) only the stop request ends it.
class SessionStop {
 public:
  explicit SessionStop(int stop_fd) : stop_fd_(stop_fd), own_(::eventfd(0, EFD_CLOEXEC)), set_(::epoll_create1(EPOLL_CLOEXEC)) {
    for (const int fd : {stop_fd_, own_}) {
      epoll_event e{};
      e.events = EPOLLIN;
      if (set_ >= 0 && (fd < 0 || ::epoll_ctl(set_, EPOLL_CTL_ADD, fd, &e) != 0)) close_set();
    }
  }
  ~SessionStop() {
    close_set();
    if (own_ >= 0) ::close(own_);
  }
  SessionStop(const SessionStop&) = delete;
  SessionStop& operator=(const SessionStop&) = delete;

  int fd() const noexcept { return set_ >= 0 ? set_ : stop_fd_; }
  // Ends the loop (receive thread); false when only a stop request can.
  bool end_session() noexcept {
    if (set_ < 0) return false;
    const std::uint64_t one = 1;
    ended_ = ::write(own_, &one, sizeof one) == sizeof one;
    return ended_;
  }
  bool ended() const noexcept { return ended_; }

 private:
  void close_set() noexcept {
    if (set_ >= 0) ::close(set_);
    set_ = -1;
  }
  int stop_fd_;
  int own_;
  int set_;
  bool ended_ = false;
};

// One session: the metadata (fetched again in each), the receiver and the stream, until a stop
// (the exit code) or, with --metadata-from-sensor, a reconfigured sensor (nullopt: start anew).
std::optional<int> run_session(const sim::apps::CommandLine& cli, Options& o, sim::apps::LiveStatus& status,
                               const sim::apps::StopSignal& stop) {
  auto config = sim::apps::ouster_stream_config(o.stream);
  if (!config) return cli.fail(config.error());
  std::optional<sim::ouster::Metadata> metadata;
  if (auto code = load_metadata(cli, o, status.line(), metadata, config->metadata_source)) return *code;
  if (config->sensor) sim::ouster::describe_live_clock(*config->sensor, *metadata);

  sim::ouster::NetworkConfig network;
  sim::apps::set_listen(network.listen, o.receive);
  network.data_port = static_cast<std::uint16_t>(o.lidar_port.value_or(metadata->udp_port_lidar));
  network.imu_port = static_cast<std::uint16_t>(o.imu_port.value_or(metadata->udp_port_imu));
  auto receiver = sim::ouster::LiveReceiver::open(network);
  if (!receiver) return cli.fail(std::string_view(receiver.error().message));
  std::printf("%s: listening on %s lidar port %u imu port %u for %s\n", tool, o.receive.bind.c_str(),
              receiver->data_port(), receiver->imu_port(), metadata->describe().c_str());
  std::fflush(stdout);
  status.check_receive_buffer(receiver->receive_buffer(), network.listen.receive_buffer);
  config->heartbeat_period = std::chrono::milliseconds(500);
  auto stream = sim::ouster::LidarStream::create(*config, *metadata);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  if (auto code = cli.apply_placement(o.stream.placement)) return *code;
  const sim::apps::HostClockSource host_clock(o.receive);

  const auto clock = poll_clock(o);
  TaiCorrection tai;
  tai.automatic = o.tai_correction == "auto";
  if (tai.automatic && !clock) {
    return cli.usage_error("--tai-correction auto takes the offset from the sensor's clock: give --sensor-ip "
                           "(or --source) and a --clock-poll-seconds above 0, or give the seconds (37)");
  }
  if (!o.tai_correction.empty() && !tai.automatic) {
    tai.applied_ns = std::llround(std::stod(o.tai_correction) * 1e9);
    stream->set_stamp_offset(-tai.applied_ns.load());
  }
  // The stream's clock check: its packets (as stamped, after the correction) against their
  // arrival, with the host's clock and what the sensor reports and the driver corrects.
  sim::timing::ClockSources sources = host_clock.sources();
  sources.reported = [&clock, &tai] { return reported_clock(clock.get(), tai); };
  stream->clock().set_sources(std::move(sources));
  const auto clock_tick = [&] {
    if (!clock) return;
    for (const auto& note : clock->take_notes()) status.line().note(sim::apps::sentence(note));
    if (!tai.automatic) return;
    const auto wanted = TaiCorrection::wanted(clock->latest());
    if (!wanted || *wanted == tai.applied_ns.load()) return;
    tai.applied_ns = *wanted;
    stream->set_stamp_offset(-*wanted);
    char text[160];
    std::snprintf(text, sizeof text,
                  "the stamps are now the sensor's less %.0f s (TAI to UTC, the current_utc_offset its "
                  "PTP master announces)", static_cast<double>(*wanted) / 1e9);
    status.line().note(text);
  };

  const std::int64_t silence_ns = network.listen.silence_timeout.count();
  const auto text = [&](bool final_line) {
    const std::string counters = stream->describe_counters();
    return o.stream.stream + " " + stream->metadata().prod_line + ": " + counters +
           sim::apps::receive_status(receiver->counters(), receiver->last_packet_ns(), silence_ns, true,
                                     final_line);
  };
  SessionStop session(stop.fd());
  ReconfigurationWatch watch;
  const auto tick = [&] {
    clock_tick();
    if (o.metadata_from_sensor && watch.due(stream->counters(), sim::monotonic_ns())) session.end_session();
  };
  receiver->run(*stream, session.fd(), sim::apps::with_clock_tick(status.callbacks(text), tick, std::chrono::seconds(1)));
  if (session.ended() && !stop.requested()) return std::nullopt;
  status.finish(stream->describe_counters(true), receiver->counters());
  return sim::apps::kExitOk;
}

int run(const sim::apps::CommandLine& cli, Options& o) {
  const auto& stop = sim::apps::StopSignal::install();
  sim::apps::LiveStatus status(tool, o.receive);
  for (;;) {
    if (auto code = run_session(cli, o, status, stop)) return *code;
    status.line().note("the sensor has sent only lidar packets of another initialization id for 2 s (it was "
                       "reconfigured or restarted): fetching its metadata again");
  }
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
