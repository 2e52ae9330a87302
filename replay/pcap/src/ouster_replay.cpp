// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap for Ouster captures: the same LidarStream (frame assembler, point and IMU
// writers) as the live driver sim_lidar_ouster. Ouster packets carry no model or format of
// their own: the sensor's metadata JSON (--calibration) is required.
#include <cstdio>
#include <span>
#include <string>

#include "ouster_replay.hpp"
#include "replay_clock.hpp"
#include "replay_common.hpp"
#include "replay_loop.hpp"
#include "sniff.hpp"
#include "sim/apps/ouster_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/clock.hpp"
#include "sim/ouster/lidar_stream.hpp"
#include "sim/ouster/route.hpp"

namespace sim::pcap {
namespace {

std::span<const std::uint8_t> as_u8(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()};
}

// The live receiver's route with the metadata's ports. Without --port and --filter, as the live
// sockets (and ouster-sdk's pcap source) take them: the lidar port to push, the IMU port to
// push_imu, other ports nowhere. With them the user chose the datagrams, whose ports may be
// anything (by_port false): the 48-byte ones are the IMU's, the rest lidar packets.
ouster::Route route_of(const ouster::Metadata& m, bool by_port) {
  return ouster::Route{.data_port = m.udp_port_lidar, .imu_port = m.udp_port_imu, .by_port = by_port};
}

class OusterTarget final : public ReplayTarget {
 public:
  OusterTarget(ouster::LidarStream stream, bool restamp, bool by_port)
      : stream_(std::move(stream)), route_(route_of(stream_.metadata(), by_port)), restamp_(restamp) {
    stream_.clock().set_base(restamp ? timing::ClockBase::restamped : timing::ClockBase::replayed);
  }

  bool takes(const Datagram& datagram) override {
    if (route_(datagram.destination.port, as_u8(datagram.payload)) != lidar::PacketKind::none) return true;
    ++other_port_;
    return false;
  }

  bool push(const Datagram& datagram) override {
    const auto bytes = as_u8(datagram.payload);
    const lidar::PacketKind kind = route_(datagram.destination.port, bytes);
    if (kind == lidar::PacketKind::data) return push_data(bytes, datagram.timestamp_ns);
    ouster::Route::push_other(stream_, kind, bytes, realtime_ns());
    return false;
  }
  void restart() override {
    stream_.reset();
    stream_.clock().restart();
  }
  void shift_stamps(std::int64_t shift_ns) override {
    stream_.set_stamp_offset(saturating_add_ns(stream_.stamp_offset(), shift_ns));
  }
  void finish() override {
    stream_.finish();
    clock_at_end(stream_);
  }
  std::uint64_t decoded_packets() const override { return stream_.counters().packets; }
  std::uint64_t frames() const override { return stream_.published().frames; }
  std::string status() const override { return stream_.describe_counters(); }
  std::string summary() const override { return stream_.describe_counters(true); }
  std::string mismatch_problem() const { return stream_.mismatch_problem(); }
  std::uint64_t other_port() const { return other_port_; }

 private:
  bool push_data(std::span<const std::uint8_t> bytes, std::int64_t capture_ns) {
    if (restamp_ && !restamped_) {
      // Shift the sensor's clock so the first packet's time is now; loops add to it.
      ouster::LidarPacket packet;
      const auto& m = stream_.metadata();
      if (ouster::LidarPacket::parse(bytes, m.format, packet, m.init_id) == ouster::PacketError::none) {
        stream_.set_stamp_offset(
            saturating_sub_ns(realtime_ns(), static_cast<std::int64_t>(packet.column(0).timestamp_ns)));
        restamped_ = true;
      }
    }
    const std::int64_t now = realtime_ns();
    const ouster::PushResult result = stream_.push(bytes, now);
    clock_replayed_packet(stream_, result.packet_ns, capture_ns, now);
    return result.frame.has_value();
  }

  ouster::LidarStream stream_;
  ouster::Route route_;
  bool restamp_;
  std::uint64_t other_port_ = 0;
  bool restamped_ = false;
};

bool ends_with(std::string_view text, std::string_view end) {
  return text.size() >= end.size() && text.substr(text.size() - end.size()) == end;
}

}  // namespace

Claim claim_ouster(const Request& request, const Sniff& sniff) {
  // A metadata JSON names the family: Hesai calibrations are CSV, Velodyne's YAML or XML.
  if (ends_with(request.calibration, ".json")) return {Evidence::calibration};
  return packets_claim(sniff.count([](auto bytes) { return ouster::guess_format(bytes).has_value(); }));
}

int run_ouster(const Request& request, Sniff& sniff) {
  apps::CommandLine cli(
      "sim_replay_pcap",
      "Replays an Ouster capture (pcap or pcapng; IPv4 fragments are reassembled) into a SIM "
      "point stream and its IMU stream, paced by the capture's timestamps, through the same "
      "frame assembler as the live driver sim_lidar_ouster. The sensor's metadata JSON "
      "(--calibration) is required.");
  ReplayArgs r;
  apps::OusterStreamOptions s;
  add_replay_options(cli, r);
  apps::add_ouster_stream_options(cli, s);
  if (auto code = cli.parse(request.argc, request.argv)) return *code;
  if (s.calibration.empty()) {
    return cli.usage_error(
        r.file + " holds Ouster lidar packets, which cannot be decoded without the sensor's "
        "metadata: give the metadata JSON recorded with it (or saved from "
        "http://SENSOR/api/v1/sensor/metadata) with --calibration FILE.json");
  }
  auto config = apps::ouster_stream_config(s);
  if (!config) return cli.fail(config.error());
  auto metadata = ouster::Metadata::load(s.calibration);
  if (!metadata) return cli.fail(std::string_view(metadata.error().message));
  // The capture is read before the streams are created: a missing one leaves nothing behind.
  if (const auto error = sniff.open_error()) return cli.fail(std::string_view(error->message));
  config->metadata_source = "file://" + std::filesystem::absolute(s.calibration).string();
  // The packets' times are the sensor's clock; an Ouster capture does not show its synchronisation.
  apps::describe_replayed_stamps(*config->sensor, r.restamp, apps::RecordedClock::sensor);
  config->heartbeat_period = std::chrono::milliseconds(500);
  const auto& stop = apps::StopSignal::install();
  auto stream = ouster::LidarStream::create(*config, *metadata);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  if (auto code = cli.apply_placement(s.placement)) return *code;
  OusterTarget target(std::move(*stream), r.restamp, !r.port && r.filter.empty());

  const ReplayResult result = replay(r, target, stop, cli.tool());
  if (target.decoded_packets() == 0 && target.other_port() != 0 && !stop.requested()) {
    return cli.fail("none of the datagrams of " + r.file + " go to the lidar port " +
                    std::to_string(metadata->udp_port_lidar) + " or the IMU port " +
                    std::to_string(metadata->udp_port_imu) + " of " + s.calibration +
                    "; give the capture's lidar port with --port");
  }
  if (target.decoded_packets() == 0 && !target.mismatch_problem().empty() && !stop.requested()) {
    return cli.fail(target.mismatch_problem() + " (" + s.calibration + " does not fit " + r.file + ")");
  }
  return finish_replay(cli, r, result, target,
                       "with the metadata " + s.calibration + " (" + metadata->describe() +
                           "); check that it belongs to this capture",
                       stop);
}

}  // namespace sim::pcap
