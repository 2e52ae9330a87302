// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap for Hesai captures: the same LidarStream (decoder, frame assembler, writer)
// as the live driver sim_lidar_hesai.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <span>
#include <string>

#include "hesai_replay.hpp"
#include "replay_clock.hpp"
#include "replay_common.hpp"
#include "replay_loop.hpp"
#include "sniff.hpp"
#include "sim/apps/hesai_options.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/clock.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/route.hpp"

namespace sim::pcap {
namespace {

std::span<const std::uint8_t> as_u8(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()};
}

// What the first Hesai packet of the capture says: its model and its number of returns.
struct Detected {
  hesai::Model model;
  unsigned returns = 1;
};

// The capture's first Hesai packet (of `forced` when given). The error explains what the
// capture holds instead.
Expected<Detected> detect(Sniff& sniff, const ReplayArgs& r, std::optional<hesai::Model> forced) {
  std::optional<Detected> detected;
  std::optional<hesai::Model> other;
  auto found = sniff.find([&](const Datagram& datagram) {
    const auto model = hesai::detect_model(as_u8(datagram.payload));
    if (!model) return false;
    if (forced && *model != *forced) {
      other = model;
      return false;
    }
    detected = Detected{*model, hesai::returns_in(as_u8(datagram.payload), *model).value_or(1)};
    return true;
  });
  if (!found) return found.error();
  if (detected) return *detected;
  const std::uint64_t seen = sniff.seen();
  const auto& stats = sniff.stats();
  const std::string on_port = r.port ? " on UDP port " + std::to_string(*r.port) : "";
  if (seen == 0) {
    return Error{ErrorCode::invalid_argument,
                 r.file + " holds " + std::to_string(stats.records) +
                     " packets but no UDP datagram" + on_port + " (" +
                     std::to_string(stats.not_udp) + " are IP but not UDP, " +
                     std::to_string(stats.not_ip) + " are not IP): it is not a LiDAR capture" +
                     (r.port ? ", or the sensor used another port (drop --port)" : "")};
  }
  if (other) {
    return Error{ErrorCode::invalid_argument,
                 r.file + " holds " + std::string(hesai::to_string(*other)) + " packets, not " +
                     std::string(hesai::to_string(*forced)) +
                     "; give the right --model or leave it out to detect it"};
  }
  return Error{ErrorCode::invalid_argument,
               "none of the " + std::to_string(seen) + " UDP datagrams" + on_port + " in " +
                   r.file + " is a Hesai point-cloud packet (models: " +
                   std::string(hesai::model_names()) +
                   ", unitree-l1, unitree-l2), nor a Velodyne or Ouster one; check the file, or "
                   "choose the sensor's port with --port"};
}

class HesaiTarget final : public ReplayTarget {
 public:
  HesaiTarget(hesai::LidarStream stream, bool restamp)
      : stream_(std::move(stream)), restamp_(restamp) {
    stream_.clock().set_base(restamp ? timing::ClockBase::restamped : timing::ClockBase::replayed);
  }

  bool takes(const Datagram& datagram) override {
    return route_(datagram.destination.port, as_u8(datagram.payload)) != lidar::PacketKind::none;
  }
  bool push(const Datagram& datagram) override {
    const auto bytes = as_u8(datagram.payload);
    if (route_(datagram.destination.port, bytes) != lidar::PacketKind::data) return false;
    return push_data(bytes, datagram.timestamp_ns);
  }
  void restart() override {
    stream_.reset();
    stream_.clock().restart();
  }
  void shift_stamps(std::int64_t shift_ns) override {
    stream_.set_stamp_offset(stream_.stamp_offset() + shift_ns);
  }
  void finish() override {
    stream_.finish();
    clock_at_end(stream_);
  }
  std::uint64_t decoded_packets() const override { return stream_.counters().packets; }
  std::uint64_t frames() const override { return stream_.published().frames; }
  std::string status() const override { return stream_.describe_counters(); }
  std::string summary() const override { return stream_.describe_counters(true); }
  hesai::Model model() const { return stream_.model(); }

 private:
  bool push_data(std::span<const std::uint8_t> payload, std::int64_t capture_ns) {
    if (restamp_ && !restamped_) {
      // Shift the sensor's clock so the first packet's time is now; loops add to it.
      hesai::Packet packet;
      if (hesai::Packet::parse(payload, stream_.model(), packet) == hesai::PacketError::none) {
        stream_.set_stamp_offset(realtime_ns() - packet.time_ns());
        restamped_ = true;
      }
    }
    const std::int64_t now = realtime_ns();
    const hesai::PushResult result = stream_.push(payload, now);
    clock_replayed_packet(stream_, result.packet_ns, capture_ns, now);
    return result.frame.has_value();
  }

  hesai::LidarStream stream_;
  // The live receiver's route: every datagram is a point-cloud packet (the stream counts what
  // is not one), as on the one port the live receiver listens to.
  hesai::Route route_;
  bool restamp_;
  bool restamped_ = false;
};

}  // namespace

Claim claim_hesai(const Request& request, const Sniff& sniff) {
  if (hesai::parse_model(request.model)) return {Evidence::model};
  return packets_claim(sniff.count([](auto bytes) { return hesai::detect_model(bytes).has_value(); }));
}

int run_hesai(const Request& request, Sniff& sniff) {
  apps::CommandLine cli(
      "sim_replay_pcap",
      "Replays a LiDAR capture (pcap or pcapng) into a SIM stream, paced by the capture's "
      "timestamps, through the same decoder and frame assembler as the live driver. The "
      "family is detected from the packets. Hesai: the model is detected and --calibration "
      "(the angle CSV) is required; the options below are Hesai's. Velodyne and Ouster: see "
      "sim_replay_pcap FILE --help (Velodyne needs --calibration FILE.yaml or db.xml, Ouster "
      "its metadata --calibration FILE.json). Unitree L1/L2: --model unitree-l2 (see "
      "sim_replay_pcap --model unitree-l2 --help).");
  ReplayArgs r;
  apps::HesaiStreamOptions s;
  add_replay_options(cli, r);
  apps::add_hesai_stream_options(cli, s);
  if (auto code = cli.parse(request.argc, request.argv)) return *code;
  if (s.calibration.empty()) {
    return cli.usage_error(
        "no calibration file given; pass the recorded unit's angle-correction CSV with "
        "--calibration (every unit has its own)");
  }
  auto configured = apps::hesai_stream_config(s);
  if (!configured) return cli.fail(configured.error());
  hesai::LidarStreamConfig config = std::move(configured.value());
  // The packets' times are the sensor's clock; a Hesai capture does not show its synchronisation.
  apps::describe_replayed_stamps(*config.sensor, r.restamp, apps::RecordedClock::sensor);
  config.heartbeat_period = std::chrono::milliseconds(500);
  // Before the stream exists: a reader may see it and stop us at once.
  const auto& stop = apps::StopSignal::install();

  auto detected = detect(sniff, r, apps::hesai_model(s));
  if (!detected) return cli.fail(std::string_view(detected.error().message));
  config.assembler.model = detected->model;
  config.returns = std::max(config.returns, detected->returns);

  auto stream = hesai::LidarStream::create(config);
  if (!stream) return cli.fail(std::string_view(stream.error().message));
  if (auto code = cli.apply_placement(s.placement)) return *code;
  HesaiTarget target(std::move(*stream), r.restamp);

  const ReplayResult result = replay(r, target, stop, cli.tool());
  return finish_replay(cli, r, result, target,
                       "as " + std::string(hesai::to_string(target.model())) +
                           "; check --model and the capture",
                       stop);
}

}  // namespace sim::pcap
