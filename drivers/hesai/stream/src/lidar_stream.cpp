// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/lidar_stream.hpp"

#include <cstdio>
#include <ostream>
#include <utility>

#include "sim/lidar/frame_publisher.hpp"

namespace sim::hesai {

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

  return LidarStream(make_pipeline(std::move(writer.value()), std::move(assembler.value())));
}

void StreamFamily::describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& pipeline) {
  const AssemblerCounters& c = pipeline.assembler.counters();
  const PublishCounters& p = pipeline.published;
  out << (machine ? " wrong_model=" : " wrong-model ") << c.wrong_model;
  const FrameAssembler& a = pipeline.assembler;
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
    out << " points/frame " << pipeline.frames.last_points();
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
}

std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
  Packet packet;
  if (Packet::parse(payload, model, packet) != PacketError::none) return std::nullopt;
  return packet.returns();
}

}  // namespace sim::hesai
