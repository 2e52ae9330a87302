// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap for Unitree L1/L2 captures: each UDP payload is a chunk of the sensor's byte
// stream, decoded by the same UnitreeStream (decoder -> SIM) as the live driver.
#include <optional>
#include <span>
#include <string>

#include "unitree_replay.hpp"
#include "replay_common.hpp"
#include "replay_loop.hpp"
#include "sniff.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/clock.hpp"
#include "sim/unitree/bytes.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/framing.hpp"
#include "sim/unitree/l2_protocol.hpp"
#include "sim/unitree/sim_sink.hpp"

namespace sim::pcap {
namespace {

// The L2's own time of the first packet in `payload` that carries one (a capture may begin
// mid-packet: the framer finds the first whole one).
std::optional<std::int64_t> first_sensor_time(std::span<const std::byte> payload) {
  unitree::L2Framer framer;
  while (!payload.empty()) {
    payload = payload.subspan(framer.feed(payload));
    while (const auto packet = framer.next()) {
      const std::uint32_t type = unitree::le::u32(*packet, 4);
      if (type == unitree::l2::point_3d) {
        if (auto header = unitree::l2::parse_point_header(*packet)) return header->stamp_ns;
      } else if (type == unitree::l2::point_2d) {
        if (auto header = unitree::l2::parse_2d_header(*packet)) return header->stamp_ns;
      } else if (type == unitree::l2::imu) {
        if (auto sample = unitree::l2::parse_imu(*packet)) return sample->stamp_ns;
      }
    }
  }
  return std::nullopt;
}

// Every datagram is a chunk of the sensor's byte stream, as on the live driver's one socket:
// the stream's framer finds the packets (points, IMU) in it.
enum class Route { bytes };
Route route(const Datagram&) { return Route::bytes; }

class UnitreeTarget final : public ReplayTarget {
 public:
  UnitreeTarget(std::unique_ptr<unitree::UnitreeStream> stream, bool restamp)
      : stream_(std::move(stream)), restamp_(restamp),
        sensor_stamps_(unitree::stream_clock_base(stream_->decoder_options(), lidar::ClockBase::sensor) ==
                       lidar::ClockBase::sensor) {}

  bool push(const Datagram& datagram) override {
    switch (route(datagram)) {
      case Route::bytes: return push_bytes(datagram.payload, datagram.timestamp_ns);
    }
    return false;
  }
  void restart() override { stream_->reset(); }
  void shift_stamps(std::int64_t shift_ns) override {
    shift_ns_ += shift_ns;
    if (sensor_stamps_) stream_->set_stamp_offset(stream_->stamp_offset() + shift_ns);
  }
  void finish() override {
    stream_->finish();
    stream_->tick_clock(realtime_ns(), true);  // even a capture shorter than a tick leaves its verdict
  }
  std::uint64_t decoded_packets() const override {
    return stream_->decoder_counters().framing.packets;
  }
  std::uint64_t frames() const override { return stream_->sink_counters().scans_published; }
  std::string status() const override { return stream_->status(); }
  std::string summary() const override {
    const auto d = stream_->decoder_counters();
    const auto& s = stream_->sink_counters();
    return "frames=" + std::to_string(s.scans_published) +
           " packets=" + std::to_string(d.framing.packets) +
           " imu=" + std::to_string(s.imu_published) +
           " failed=" + std::to_string(s.publish_failures);
  }

 private:
  bool push_bytes(std::span<const std::byte> payload, std::int64_t capture_ns) {
    const std::uint64_t before = stream_->sink_counters().scans_published;
    const std::int64_t now = realtime_ns();
    if (sensor_stamps_) {
      push_sensor_stamped(payload, capture_ns, now);
    } else {
      // Scans are stamped with the time their bytes arrived: the capture's (moved on by loops),
      // or the present with --restamp.
      if (restamp_ && restamp_offset_ == 0) restamp_offset_ = now - capture_ns;
      stream_->push(payload, capture_ns + shift_ns_ + restamp_offset_);
    }
    stream_->tick_clock(now);
    return stream_->sink_counters().scans_published > before;
  }

  // --sensor-time: the packets' own times are the stamps, measured against the capture's time
  // of their record (moved on by loops like the stamps), or with --restamp moved to the present
  // and measured against this host's clock now.
  void push_sensor_stamped(std::span<const std::byte> payload, std::int64_t capture_ns, std::int64_t now) {
    if (restamp_ && !restamped_) {
      if (const auto first = first_sensor_time(payload)) {
        stream_->set_stamp_offset(stream_->stamp_offset() + (now - *first));
        restamped_ = true;
      }
    }
    stream_->push(payload, restamp_ ? now : capture_ns + shift_ns_);
  }

  std::unique_ptr<unitree::UnitreeStream> stream_;
  bool restamp_;
  bool sensor_stamps_;
  bool restamped_ = false;
  std::int64_t restamp_offset_ = 0;
  std::int64_t shift_ns_ = 0;
};

}  // namespace

Claim claim_unitree(const Request& request, const Sniff& /*sniff*/) {
  return unitree::parse_model(request.model) ? Claim{Evidence::model} : Claim{};
}

int run_unitree(const Request& request, Sniff& sniff) {
  apps::CommandLine cli(
      "sim_replay_pcap",
      "Replays a Unitree L1 or L2 capture (pcap or pcapng of the sensor's UDP stream) into a "
      "SIM point stream and its IMU stream, paced by the capture's timestamps, through the same "
      "decoder as the live driver sim_lidar_unitree.");
  ReplayArgs r;
  std::string model_text;
  unitree::UnitreeStreamOptions o;
  std::uint32_t scan_packets = o.decoder.packets_per_scan;
  auto& app = cli.app();
  add_replay_options(cli, r);
  app.add_option("--model", model_text, "unitree-l1 or unitree-l2")
      ->required()
      ->check(apps::validator(unitree::model_problem, "MODEL"));
  cli.add_stream("--stream", o.points_stream, "SIM point stream, e.g. /lidar_top")->required();
  cli.add_stream("--imu-stream", o.imu_stream, "SIM IMU stream (empty: <stream>.imu)");
  app.add_flag("--no-imu", o.no_imu, "do not publish IMU samples");
  app.add_option("--scan-packets", scan_packets, "packets per published scan")
      ->check(CLI::Range(1U, 1000U));
  app.add_flag("--checksum", o.checksum, "publish frames with an XXH3 checksum");
  bool sensor_time = false;
  app.add_flag("--sensor-time", sensor_time,
               "stamp frames with the L2's own clock (its packets' times) instead of the capture's");
  apps::SensorOptions sensor;
  apps::add_sensor_options(cli, sensor, apps::SensorKind::lidar);
  ThreadPlacement placement;
  cli.add_placement(placement);
  if (auto code = cli.parse(request.argc, request.argv)) return *code;
  auto described = apps::sensor_info_from(sensor, o.points_stream);
  if (!described) return cli.fail(described.error());
  o.sensor = std::move(described.value());
  // Scans are stamped with the capture's times, or the L2's own (see UnitreeTarget::push).
  apps::describe_replayed_stamps(*o.sensor, r.restamp,
                                 sensor_time ? apps::RecordedClock::sensor : apps::RecordedClock::capturing_host);
  const auto& stop = apps::StopSignal::install();
  if (auto code = cli.apply_placement(placement)) return *code;
  o.decoder.model = *unitree::parse_model(model_text);
  o.decoder.packets_per_scan = scan_packets;
  // The capture's time (the recording host's clock), or the L2's own clock as recorded.
  o.decoder.time_source = sensor_time ? unitree::TimeSource::sensor : unitree::TimeSource::host;
  o.sensor_clock_base = r.restamp ? lidar::ClockBase::restamped : lidar::ClockBase::replayed;

  // The file is read before the streams are created: a missing capture leaves nothing behind.
  if (const auto error = sniff.open_error()) return cli.fail(std::string_view(error->message));
  auto stream = unitree::UnitreeStream::create(o);
  if (!stream) return cli.fail(stream.error());
  UnitreeTarget target(std::move(*stream), r.restamp);
  const ReplayResult result = replay(r, target, stop, cli.tool());
  return finish_replay(cli, r, result, target,
                       std::string("as Unitree ") + unitree::to_string(o.decoder.model) +
                           " packets with a good checksum; check --model and the capture",
                       stop);
}

}  // namespace sim::pcap
