// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/lidar_stream.hpp"

#include <cstdio>
#include <sstream>
#include <utility>

#include "sim/lidar_point.hpp"

namespace sim::hesai {

struct LidarStream::Impl {
  Impl(Writer w, FrameAssembler a) : writer(std::move(w)), assembler(std::move(a)) {}

  // The loan keeps a pointer to the writer, so the writer must not move: Impl lives on the
  // heap and is never moved itself.
  Writer writer;
  FrameAssembler assembler;
  Loan loan;
  PublishCounters published;
  std::size_t last_points = 0;
  std::int64_t stamp_offset_ns = 0;

  void attach() noexcept {
    loan = Loan{};  // a writer lends one slot at a time: give back the one still open first
    loan = writer.loan();
    assembler.set_output(loan.as<LidarPoint>());
  }

  void publish(const CompletedFrame& frame) noexcept {
    const WriteStatus status =
        std::move(loan).commit(frame.point_count * sizeof(LidarPoint), frame.stamp_ns + stamp_offset_ns,
                    frame.host_receive_ns);
    if (status == WriteStatus::ok) {
      ++published.frames;
      published.points += frame.point_count;
      if (!frame.whole_revolution) ++published.partial_frames;
      last_points = frame.point_count;
    } else {
      ++published.failed;
    }
    attach();  // the next revolution goes to the new back slot
  }
};

namespace {

// The configured description completed with what the stream itself knows.
SensorInfo describe_sensor(const LidarStreamConfig& config, Model model) {
  SensorInfo info = *config.sensor;
  info.point_time = PointTime::after_frame_stamp;
  if (info.identity.vendor.empty()) info.identity.vendor = "Hesai";
  if (info.identity.model.empty()) info.identity.model = std::string(to_string(model));
  if (info.calibration_source.empty()) {
    std::error_code ignored;
    const auto file = std::filesystem::absolute(config.calibration, ignored).lexically_normal();
    info.calibration_source = ("file://" + file.string()).substr(0, SensorInfo::kMaxSource);
  }
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

  StreamSpec spec;
  spec.name = config.stream;
  spec.layout = Layout::of(PointLayout::of(
      PointType::lidar_point, frame_capacity(model, config.returns, config.min_rpm)));
  spec.checksum = config.checksum;
  spec.lock_memory = config.lock_memory;
  spec.heartbeat_period = config.heartbeat_period;
  if (config.sensor) spec.sensor = describe_sensor(config, model);
  auto writer = Writer::create(spec);
  if (!writer) return writer.error();

  auto impl = std::make_unique<Impl>(std::move(writer.value()), std::move(assembler.value()));
  impl->attach();
  return LidarStream(std::move(impl));
}

LidarStream::LidarStream(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LidarStream::LidarStream(LidarStream&&) noexcept = default;
LidarStream& LidarStream::operator=(LidarStream&&) noexcept = default;
LidarStream::~LidarStream() = default;

PushResult LidarStream::push(std::span<const std::uint8_t> payload,
                             std::int64_t host_receive_ns) noexcept {
  PushResult result = impl_->assembler.push(payload, host_receive_ns);
  if (result.frame) impl_->publish(*result.frame);
  return result;
}

std::optional<CompletedFrame> LidarStream::finish() noexcept {
  if (!impl_->assembler.options().emit_partial_frames) {
    impl_->assembler.reset();
    return std::nullopt;
  }
  std::optional<CompletedFrame> frame = impl_->assembler.flush();
  if (frame) impl_->publish(*frame);
  return frame;
}

void LidarStream::reset() noexcept { impl_->assembler.reset(); }
void LidarStream::set_stamp_offset(std::int64_t offset_ns) noexcept { impl_->stamp_offset_ns = offset_ns; }
std::int64_t LidarStream::stamp_offset() const noexcept { return impl_->stamp_offset_ns; }

Model LidarStream::model() const noexcept { return impl_->assembler.options().model; }
const AssemblerCounters& LidarStream::counters() const noexcept { return impl_->assembler.counters(); }
const PublishCounters& LidarStream::published() const noexcept { return impl_->published; }
std::optional<std::int64_t> LidarStream::time_to_cut_ns() const noexcept {
  return impl_->assembler.time_to_cut_ns();
}
std::uint64_t LidarStream::max_points() const noexcept {
  return impl_->writer.layout().points.max_points;
}
Writer& LidarStream::writer() noexcept { return impl_->writer; }

std::string LidarStream::describe_counters(bool machine) const {
  const AssemblerCounters& c = impl_->assembler.counters();
  const PublishCounters& p = impl_->published;
  std::ostringstream out;
  const char* sep = machine ? "=" : " ";
  out << "frames" << sep << p.frames << " packets" << sep << c.packets << " lost" << sep
      << c.lost_packets << " malformed" << sep << c.malformed << (machine ? " wrong_model" : " wrong-model")
      << sep << c.wrong_model;
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
    out << " points/frame " << impl_->last_points;
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
