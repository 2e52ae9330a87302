// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/lidar_stream.hpp"

#include <cstdio>
#include <sstream>
#include <utility>

#include "sim/lidar/frame_publisher.hpp"

namespace sim::hesai {

struct LidarStream::Impl : lidar::PointPipeline<FrameAssembler, PublishCounters> {
  using PointPipeline::PointPipeline;
};

namespace {

// The configured description completed with what the stream itself knows.
SensorInfo describe_sensor(const LidarStreamConfig& config, Model model) {
  SensorInfo info = *config.sensor;
  info.point_time = PointTime::after_frame_stamp;
  if (info.identity.vendor.empty()) info.identity.vendor = "Hesai";
  if (info.identity.model.empty()) info.identity.model = std::string(to_string(model));
  if (info.calibration_source.empty()) info.calibration_source = lidar::file_source(config.calibration);
  return info;
}

}  // namespace

Expected<LidarStream> LidarStream::create(const LidarStreamConfig& config) {
  const Model model = config.assembler.model;
  if (config.calibration.empty()) {
    return Error{ErrorCode::invalid_argument,
                 "no calibration file given; pass the sensor's angle-correction CSV with "
                 "--calibration (every unit has its own)."};
  }
  auto calibration = Calibration::load(config.calibration, model);
  if (!calibration) return calibration.error();
  AssemblerOptions options = config.assembler;
  if (config.firetimes) {
    auto firetimes = FiretimeCorrection::load(*config.firetimes, model);
    if (!firetimes) return firetimes.error();
    options.firetimes = std::move(firetimes.value());
  }
  auto assembler = FrameAssembler::create(std::move(calibration.value()), std::move(options));
  if (!assembler) return assembler.error();

  StreamSpec spec = lidar::point_stream_spec(config, frame_capacity(model, config.returns, config.min_rpm));
  if (config.sensor) spec.sensor = describe_sensor(config, model);
  auto writer = Writer::create(spec);
  if (!writer) return writer.error();

  return LidarStream(std::make_unique<Impl>(std::move(writer.value()), std::move(assembler.value())));
}

LidarStream::LidarStream(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LidarStream::LidarStream(LidarStream&&) noexcept = default;
LidarStream& LidarStream::operator=(LidarStream&&) noexcept = default;
LidarStream::~LidarStream() = default;

PushResult LidarStream::push(std::span<const std::uint8_t> payload,
                             std::int64_t host_receive_ns) noexcept {
  return impl_->push(payload, host_receive_ns);
}

std::optional<CompletedFrame> LidarStream::finish() noexcept {
  if (!impl_->assembler.options().emit_partial_frames) {
    impl_->assembler.reset();
    return std::nullopt;
  }
  return impl_->finish();
}

void LidarStream::reset() noexcept { impl_->assembler.reset(); }
void LidarStream::set_stamp_offset(std::int64_t offset_ns) noexcept { impl_->frames.set_stamp_offset(offset_ns); }
std::int64_t LidarStream::stamp_offset() const noexcept { return impl_->frames.stamp_offset(); }

Model LidarStream::model() const noexcept { return impl_->assembler.options().model; }
const AssemblerCounters& LidarStream::counters() const noexcept { return impl_->assembler.counters(); }
const PublishCounters& LidarStream::published() const noexcept { return impl_->published; }
std::optional<std::int64_t> LidarStream::time_to_cut_ns() const noexcept {
  return impl_->assembler.time_to_cut_ns();
}
std::uint64_t LidarStream::max_points() const noexcept { return impl_->frames.max_points(); }
Writer& LidarStream::writer() noexcept { return impl_->frames.writer(); }
timing::ClockReporter& LidarStream::clock() noexcept { return impl_->clock; }
std::optional<ClockStatus> LidarStream::tick_clock(std::int64_t now_realtime_ns, bool at_once) {
  return impl_->tick_clock(now_realtime_ns, at_once);
}

std::string LidarStream::describe_counters(bool machine) const {
  const AssemblerCounters& c = impl_->assembler.counters();
  const PublishCounters& p = impl_->published;
  std::ostringstream out;
  lidar::describe_frames(out, machine, p.frames, c.packets, c.lost_packets, c.malformed);
  out << (machine ? " wrong_model=" : " wrong-model ") << c.wrong_model;
  const FrameAssembler& a = impl_->assembler;
  const auto& safety = a.functional_safety();
  if (machine) {
    out << " out_of_order=" << c.out_of_order << " points=" << p.points
        << " partial_frames=" << p.partial_frames << " dropped_points=" << c.dropped_points
        << " publish_failures=" << p.failed << " crc_errors=" << c.crc_errors
        << " rpm=" << a.motor_rpm();
    if (safety) {
      std::string state = to_string(safety->state);
      for (char& ch : state) ch = ch == ' ' ? '_' : ch;
      out << " safety=" << state << " fault_code=" << safety->fault_code;
    }
  } else {
    out << " points/frame " << impl_->frames.last_points();
    if (c.dropped_points != 0) out << " dropped-points " << c.dropped_points;
    if (c.crc_errors != 0) out << " crc-errors " << c.crc_errors;
    if (a.motor_rpm() != 0) out << " rpm " << a.motor_rpm();
    // The QT128's functional safety: what a user must see when the sensor distrusts itself.
    if (safety) {
      out << " safety " << to_string(safety->state);
      if (safety->fault_type != FaultCodeType::none) {
        char code[8];
        std::snprintf(code, sizeof code, "%04X", safety->fault_code);
        out << " fault 0x" << code
            << (safety->fault_type == FaultCodeType::current ? " (current)" : " (past)");
      }
    }
  }
  return out.str();
}

std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
  Packet packet;
  if (Packet::parse(payload, model, packet) != PacketError::none) return std::nullopt;
  return packet.returns();
}

}  // namespace sim::hesai
