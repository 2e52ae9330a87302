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

#include "replay_clock.hpp"
#include "replay_loop.hpp"
#include "velodyne_replay.hpp"
#include "replay_common.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/velodyne_options.hpp"
#include "sim/clock.hpp"
#include "sim/velodyne/lidar_stream.hpp"

namespace sim::pcap {
namespace {

std::span<const std::uint8_t> as_u8(std::span<const std::byte> bytes) {
  return {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()};
}

bool is_capture_name(std::string_view arg) {
  const auto ends = [&](std::string_view end) {
    return arg.size() >= end.size() && arg.substr(arg.size() - end.size()) == end;
  };
  return !arg.empty() && arg.front() != '-' && (ends(".pcap") || ends(".pcapng"));
}

struct Detected {
  velodyne::Model model;
  unsigned returns = 1;
};

// Reads the capture up to its first Velodyne data packet (of `forced` when given).
Expected<Detected> detect(const ReplayArgs& r, std::optional<velodyne::Model> forced) {
  auto reader = CaptureReader::open(r.file, r.capture_options());
  if (!reader) return reader.error();
  Datagram datagram;
  std::optional<velodyne::Model> other;
  std::uint64_t seen = 0;
  std::uint64_t unnamed = 0;  // HDL-32E packets of firmware before 2.2.20
  for (;;) {
    const NextStatus status = reader->next(datagram);
    if (status == NextStatus::error) return reader->error();
    if (status == NextStatus::end) break;
    ++seen;
    const auto bytes = as_u8(datagram.payload);
    if (velodyne::is_unnamed_hdl32e(bytes)) {
      if (forced == velodyne::Model::hdl32e) return Detected{velodyne::Model::hdl32e, 1};
      ++unnamed;
      continue;
    }
    const auto model = velodyne::detect_model(bytes);
    if (!model) continue;
    if (forced && *model != *forced) {
      other = model;
      continue;
    }
    return Detected{*model, velodyne::returns_in(bytes, *model).value_or(1)};
  }
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

  bool push(std::span<const std::byte> payload, std::int64_t capture_ns) override {
    const auto bytes = as_u8(payload);
    if (bytes.size() != velodyne::packet_size) {
      stream_.push_position(bytes);  // port 8308's GPRMC/PPS packets (or a stray datagram)
      return false;
    }
    if (restamp_ && !restamped_) {
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
  velodyne::LidarStream stream_;
  bool restamp_;
  bool restamped_ = false;
};

}  // namespace

bool is_velodyne_replay(int argc, char** argv) {
  std::string capture;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    std::string_view value;
    if (arg == "--model" && i + 1 < argc) value = argv[i + 1];
    if (arg.rfind("--model=", 0) == 0) value = arg.substr(8);
    if (!value.empty()) return velodyne::parse_model(value).has_value();
    // Velodyne calibrations are ros-drivers YAML or db.xml (Hesai's are CSV, Ouster's JSON):
    // then the Velodyne replay explains a capture it cannot decode, not the Hesai one.
    if (arg == "--calibration" && i + 1 < argc) value = argv[i + 1];
    if (arg.rfind("--calibration=", 0) == 0) value = arg.substr(14);
    const auto ends = [&](std::string_view end) {
      return value.size() >= end.size() && value.substr(value.size() - end.size()) == end;
    };
    if (ends(".yaml") || ends(".yml") || ends(".xml")) return true;
    if (is_capture_name(arg)) capture = arg;
  }
  if (capture.empty()) return false;
  auto reader = CaptureReader::open(capture, detection_options(argc, argv));
  if (!reader) return false;  // the Hesai replay explains the file
  Datagram datagram;
  for (unsigned seen = 0; seen < 256 && reader->next(datagram) == NextStatus::datagram; ++seen) {
    const auto bytes = as_u8(datagram.payload);
    if (velodyne::detect_model(bytes) || velodyne::is_unnamed_hdl32e(bytes)) return true;
  }
  return false;
}

int run_velodyne_replay(int argc, char** argv) {
  apps::CommandLine cli(
      "sim_replay_pcap",
      "Replays a Velodyne capture (pcap or pcapng) into a SIM stream, paced by the capture's "
      "timestamps, through the same decoder and frame assembler as the live driver "
      "sim_lidar_velodyne. The model is detected from the packets; --calibration is required.");
  ReplayArgs r;
  apps::VelodyneStreamOptions s;
  add_replay_options(cli, r);
  apps::add_velodyne_stream_options(cli, s);
  if (auto code = cli.parse(argc, argv)) return *code;
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

  auto detected = detect(r, apps::velodyne_model(s));
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
