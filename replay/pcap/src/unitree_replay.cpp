// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap for Unitree L1/L2 captures: each UDP payload is a chunk of the sensor's byte
// stream, decoded by the same LidarStream (decoder -> SIM) as the live driver.
#include <optional>
#include <span>
#include <string>

#include "unitree_replay.hpp"
#include "replay_common.hpp"
#include "replay_loop.hpp"
#include "sniff.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/unitree_options.hpp"
#include "sim/clock.hpp"
#include "sim/unitree/bytes.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/framing.hpp"
#include "sim/unitree/l2_protocol.hpp"
#include "sim/unitree/lidar_stream.hpp"

namespace sim::pcap {
namespace {

// The L2's own time of the first packet in `payload` that carries one (a capture may begin
// mid-packet: the framer finds the first whole one).
std::optional<std::int64_t> first_sensor_time(std::span<const std::uint8_t> payload) {
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
  UnitreeTarget(unitree::LidarStream stream, bool restamp)
      : stream_(std::move(stream)), restamp_(restamp),
        sensor_stamps_(unitree::stream_clock_base(stream_.options(), timing::ClockBase::sensor) ==
                       timing::ClockBase::sensor) {}

  bool push(const Datagram& datagram) override {
    const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(datagram.payload.data()),
                                              datagram.payload.size());
    switch (route(datagram)) {
      case Route::bytes: return push_bytes(bytes, datagram.timestamp_ns);
    }
    return false;
  }
  void restart() override {
    stream_.reset();
    stream_.clock().restart();
  }
  void shift_stamps(std::int64_t shift_ns) override {
    shift_ns_ += shift_ns;
    if (sensor_stamps_) stream_.set_stamp_offset(stream_.stamp_offset() + shift_ns);
  }
  void finish() override {
    stream_.finish();
    stream_.tick_clock(realtime_ns(), true);  // even a capture shorter than a tick leaves its verdict
  }
  std::uint64_t decoded_packets() const override { return stream_.counters().framing.packets; }
  std::uint64_t frames() const override { return stream_.published().frames; }
  std::string status() const override { return stream_.describe_counters(); }
  std::string summary() const override { return stream_.describe_counters(true); }
  unitree::Model model() const { return stream_.model(); }

 private:
  bool push_bytes(std::span<const std::uint8_t> payload, std::int64_t capture_ns) {
    const std::int64_t now = realtime_ns();
    std::size_t published = 0;
    if (sensor_stamps_) {
      published = push_sensor_stamped(payload, capture_ns, now);
    } else {
      // Scans are stamped with the time their bytes arrived: the capture's (moved on by loops),
      // or the present with --restamp.
      if (restamp_ && restamp_offset_ == 0) restamp_offset_ = now - capture_ns;
      published = stream_.push(payload, capture_ns + shift_ns_ + restamp_offset_);
    }
    stream_.tick_clock(now);
    return published != 0;
  }

  // --sensor-time: the packets' own times are the stamps, measured against the capture's time
  // of their record (moved on by loops like the stamps), or with --restamp moved to the present
  // and measured against this host's clock now.
  std::size_t push_sensor_stamped(std::span<const std::uint8_t> payload, std::int64_t capture_ns, std::int64_t now) {
    if (restamp_ && !restamped_) {
      if (const auto first = first_sensor_time(payload)) {
        stream_.set_stamp_offset(stream_.stamp_offset() + (now - *first));
        restamped_ = true;
      }
    }
    return stream_.push(payload, restamp_ ? now : capture_ns + shift_ns_);
  }

  unitree::LidarStream stream_;
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
  apps::UnitreeStreamOptions s;
  add_replay_options(cli, r);
  apps::add_unitree_stream_options(cli, s);
  if (auto code = cli.parse(request.argc, request.argv)) return *code;
  auto config = apps::unitree_stream_config(s);
  if (!config) return cli.fail(config.error());
  // Scans are stamped with the capture's times, or the L2's own (see UnitreeTarget::push).
  apps::describe_replayed_stamps(*config->sensor, r.restamp,
                                 s.sensor_time ? apps::RecordedClock::sensor : apps::RecordedClock::capturing_host);
  config->sensor_clock_base = r.restamp ? timing::ClockBase::restamped : timing::ClockBase::replayed;
  const auto& stop = apps::StopSignal::install();
  if (auto code = cli.apply_placement(s.placement)) return *code;

  // The capture is read before the streams are created: a missing one leaves nothing behind.
  if (const auto error = sniff.open_error()) return cli.fail(std::string_view(error->message));
  auto stream = unitree::LidarStream::create(*config);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  UnitreeTarget target(std::move(*stream), r.restamp);
  const ReplayResult result = replay(r, target, stop, cli.tool());
  return finish_replay(cli, r, result, target,
                       std::string("as Unitree ") + unitree::to_string(target.model()) +
                           " packets with a good checksum; check --model and the capture",
                       stop);
}

}  // namespace sim::pcap
