// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap for Velodyne captures: the same LidarStream (decoder, frame assembler, writer,
// position packets) as the live driver sim_lidar_velodyne. A packet's timestamp counts
// microseconds past the hour; the capture's own time picks the hour, so an old recording
// replays with its own stamps.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <span>
#include <string>

#include "velodyne_replay.hpp"
#include "replay_clock.hpp"
#include "replay_common.hpp"
#include "replay_loop.hpp"
#include "sniff.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/velodyne_options.hpp"
#include "sim/clock.hpp"
#include "sim/velodyne/lidar_stream.hpp"
#include "sim/velodyne/route.hpp"

namespace sim::pcap {
namespace {

std::span<const std::uint8_t> as_u8(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()};
}

bool ends_with(std::string_view text, std::string_view end) {
  return text.size() >= end.size() && text.substr(text.size() - end.size()) == end;
}

struct Detected {
  velodyne::Model model;
  unsigned returns = 1;
};

// The capture's first Velodyne data packet (of `forced` when given). The error explains what
// the capture holds instead.
Expected<Detected> detect(Sniff& sniff, const ReplayArgs& r, std::optional<velodyne::Model> forced) {
  std::optional<Detected> detected;
  std::optional<velodyne::Model> other;
  std::uint64_t unnamed = 0;  // HDL-32E packets of firmware before 2.2.20
  auto found = sniff.find([&](const Datagram& datagram) {
    const auto bytes = as_u8(datagram.payload);
    if (velodyne::is_unnamed_hdl32e(bytes)) {
      if (forced == velodyne::Model::hdl32e) detected = Detected{velodyne::Model::hdl32e, 1};
      ++unnamed;
      return detected.has_value();
    }
    const auto model = velodyne::detect_model(bytes);
    if (!model) return false;
    if (forced && *model != *forced) {
      other = model;
      return false;
    }
    detected = Detected{*model, velodyne::returns_in(bytes, *model).value_or(1)};
    return true;
  });
  if (!found) return found.error();
  if (detected) return *detected;
  const std::uint64_t seen = sniff.seen();
  if (other) {
    return Error{ErrorCode::invalid_argument,
                 r.file + " holds " + std::string(velodyne::to_string(*other)) + " packets, not " +
                     std::string(velodyne::to_string(*forced)) + "; give the right --model or leave it out"};
  }
  if (unnamed != 0) {
    return Error{ErrorCode::invalid_argument,
                 std::to_string(unnamed) + " of the " + std::to_string(seen) + " UDP datagrams in " + r.file +
                     " are Velodyne data packets that do not name their model (product ID 0), as an "
                     "HDL-32E with firmware before 2.2.20 sends them; give --model HDL-32E"};
  }
  return Error{ErrorCode::invalid_argument,
               "none of the " + std::to_string(seen) + " UDP datagrams in " + r.file +
                   " is a Velodyne data packet (1206 bytes, models: " + std::string(velodyne::model_names()) +
                   "); check the file, or choose the sensor's port with --port"};
}

class VelodyneTarget final : public ReplayTarget {
 public:
  VelodyneTarget(velodyne::LidarStream stream, bool restamp) : stream_(std::move(stream)), restamp_(restamp) {
    stream_.clock().set_base(restamp ? timing::ClockBase::restamped : timing::ClockBase::replayed);
  }

  bool takes(const Datagram& datagram) override {
    return route_(datagram.destination.port, as_u8(datagram.payload)) != lidar::PacketKind::none;
  }
  bool push(const Datagram& datagram) override {
    const auto bytes = as_u8(datagram.payload);
    const lidar::PacketKind kind = route_(datagram.destination.port, bytes);
    if (kind == lidar::PacketKind::data) return push_data(bytes, datagram.timestamp_ns);
    velodyne::Route::push_other(stream_, kind, bytes, realtime_ns());
    return false;
  }
  void restart() override {
    stream_.reset();
    stream_.clock().restart();
  }
  void shift_stamps(std::int64_t shift_ns) override { stream_.set_stamp_offset(stream_.stamp_offset() + shift_ns); }
  void finish() override {
    stream_.finish();
    clock_at_end(stream_);
  }
  std::uint64_t decoded_packets() const override { return stream_.counters().packets; }
  std::uint64_t frames() const override { return stream_.published().frames; }
  std::string status() const override { return stream_.describe_counters(); }
  std::string summary() const override { return stream_.describe_counters(true); }
  velodyne::Model model() const { return stream_.model(); }

 private:
  bool push_data(std::span<const std::uint8_t> bytes, std::int64_t capture_ns) {
    // A datagram to the data port may be shorter than a data packet (the stream counts it):
    // its timestamp is read only from one of the right size.
    if (restamp_ && !restamped_ && bytes.size() == velodyne::packet_size) {
      // Shift the sensor's clock so the first packet's time is now; loops add to it.
      stream_.set_stamp_offset(realtime_ns() - velodyne::packet_time_ns(velodyne::Packet::read_u32(
                                                   bytes.data() + velodyne::timestamp_offset), capture_ns));
      restamped_ = true;
    }
    const std::int64_t now = realtime_ns();
    const velodyne::PushResult result = stream_.push(bytes, now, capture_ns);
    clock_replayed_packet(stream_, result.packet_ns, capture_ns, now);
    return result.frame.has_value();
  }

  velodyne::LidarStream stream_;
  // The live receiver's route with the sensor's default ports: a datagram to 2368 is a data
  // packet, one to 8308 a position packet (GPRMC, PPS), as the live sockets take them; one to
  // another port (a sensor set to other ports, or a capture filtered with --port or --filter)
  // by its size: 1206 bytes are data, the rest position packets or strays the stream counts.
  velodyne::Route route_;
  bool restamp_;
  bool restamped_ = false;
};

}  // namespace

Claim claim_velodyne(const Request& request, const Sniff& sniff) {
  if (velodyne::parse_model(request.model)) return {Evidence::model};
  // Velodyne calibrations are ros-drivers YAML or db.xml (Hesai's are CSV, Ouster's JSON):
  // then the Velodyne replay explains a capture it cannot decode.
  const std::string_view calibration = request.calibration;
  if (ends_with(calibration, ".yaml") || ends_with(calibration, ".yml") || ends_with(calibration, ".xml")) {
    return {Evidence::calibration};
  }
  return packets_claim(sniff.count(
      [](auto bytes) { return velodyne::detect_model(bytes).has_value() || velodyne::is_unnamed_hdl32e(bytes); }));
}

int run_velodyne(const Request& request, Sniff& sniff) {
  apps::CommandLine cli(
      "sim_replay_pcap",
      "Replays a Velodyne capture (pcap or pcapng) into a SIM stream, paced by the capture's "
      "timestamps, through the same decoder and frame assembler as the live driver "
      "sim_lidar_velodyne. The model is detected from the packets; --calibration is required.");
  ReplayArgs r;
  apps::VelodyneStreamOptions s;
  add_replay_options(cli, r);
  apps::add_velodyne_stream_options(cli, s);
  if (auto code = cli.parse(request.argc, request.argv)) return *code;
  if (s.calibration.empty()) {
    return cli.usage_error(
        "no calibration file given; pass the recorded sensor's YAML (nominal tables in "
        "/usr/share/sim/velodyne) or its db.xml with --calibration");
  }
  auto config = apps::velodyne_stream_config(s);
  if (!config) return cli.fail(config.error());
  // The packets' times are the sensor's clock, whose synchronisation the recorded position
  // packets show; with --restamp they are this host's, which those packets must not change.
  apps::describe_replayed_stamps(*config->sensor, r.restamp, apps::RecordedClock::sensor_with_position);
  config->stamp_clock = r.restamp ? velodyne::StampClock::restamped : velodyne::StampClock::sensor_recorded;
  config->heartbeat_period = std::chrono::milliseconds(500);
  const auto& stop = apps::StopSignal::install();

  auto detected = detect(sniff, r, apps::velodyne_model(s));
  if (!detected) return cli.fail(std::string_view(detected.error().message));
  config->assembler.model = detected->model;
  config->returns = std::max(config->returns, detected->returns);
  auto stream = velodyne::LidarStream::create(*config);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  if (auto code = cli.apply_placement(s.placement)) return *code;
  VelodyneTarget target(std::move(*stream), r.restamp);

  const ReplayResult result = replay(r, target, stop, cli.tool());
  return finish_replay(cli, r, result, target,
                       "as " + std::string(velodyne::to_string(target.model())) + "; check --model and the capture",
                       stop);
}

}  // namespace sim::pcap
