// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/lidar_stream.hpp"

#include <sstream>
#include <utility>

#include "sim/lidar_point.hpp"

namespace sim::velodyne {

TimeSync time_sync_of(const PositionReport& report) {
  TimeSync sync;
  const std::string gprmc = !report.has_gprmc ? "no GPRMC" : report.gprmc_valid ? "GPRMC valid" : "GPRMC no fix";
  const bool pps_locked = report.pps == PpsState::locked;
  if (report.pps == PpsState::unknown) {
    sync.text = gprmc;  // HDL-32E/64E position packets carry no PPS state
    sync.base = report.gprmc_valid ? TimeBase::sensor_synchronized : TimeBase::sensor_free_running;
  } else {
    sync.text = std::string("PPS ") + to_string(report.pps) + ", " + gprmc;
    sync.base = pps_locked ? TimeBase::sensor_synchronized : TimeBase::sensor_free_running;
  }
  return sync;
}

struct LidarStream::Impl {
  Impl(Writer w, FrameAssembler a) : writer(std::move(w)), assembler(std::move(a)) {}

  // The loan points at the writer: Impl lives on the heap and never moves.
  Writer writer;
  FrameAssembler assembler;
  Loan loan;
  PublishCounters published;
  std::size_t last_points = 0;
  std::int64_t stamp_offset_ns = 0;
  std::optional<SensorInfo> sensor;  // the description, re-set when the time sync changes
  TimeSync sync;

  void attach() noexcept {
    loan = Loan{};  // a writer lends one slot at a time
    loan = writer.loan();
    assembler.set_output(loan.as<LidarPoint>());
  }

  void publish(const CompletedFrame& frame) noexcept {
    const WriteStatus status = std::move(loan).commit(
        frame.point_count * sizeof(LidarPoint), frame.stamp_ns + stamp_offset_ns, frame.host_receive_ns);
    if (status == WriteStatus::ok) {
      ++published.frames;
      published.points += frame.point_count;
      if (!frame.whole_revolution) ++published.partial_frames;
      last_points = frame.point_count;
    } else {
      ++published.failed;
    }
    attach();
  }
};

Expected<LidarStream> LidarStream::create(const LidarStreamConfig& config) {
  const Model model = config.assembler.model;
  if (config.calibration.empty()) {
    return Error{ErrorCode::invalid_argument,
                 "no calibration file given; pass the sensor's YAML (the nominal tables are in "
                 "/usr/share/sim/velodyne) or an HDL-64E's db.xml with --calibration."};
  }
  auto calibration = Calibration::load(config.calibration);
  if (!calibration) return calibration.error();
  auto assembler = FrameAssembler::create(std::move(calibration.value()), config.assembler);
  if (!assembler) return assembler.error();

  StreamSpec spec;
  spec.name = config.stream;
  spec.layout = Layout::of(PointLayout::of(PointType::lidar_point,
                                           frame_capacity(model, config.returns, config.min_rpm)));
  spec.checksum = config.checksum;
  spec.lock_memory = config.lock_memory;
  spec.heartbeat_period = config.heartbeat_period;
  std::optional<SensorInfo> sensor = config.sensor;
  if (sensor) {
    sensor->identity.vendor = "Velodyne";
    sensor->identity.model = std::string(to_string(model));
    sensor->calibration_source = ("file://" + std::filesystem::absolute(config.calibration).string())
                                     .substr(0, SensorInfo::kMaxSource);
    sensor->point_time = PointTime::after_frame_stamp;
    sensor->time_base = TimeBase::unknown;
    sensor->time_sync = TimeSync{}.text;
    spec.sensor = sensor;
  }
  auto writer = Writer::create(spec);
  if (!writer) return writer.error();

  auto impl = std::make_unique<Impl>(std::move(writer.value()), std::move(assembler.value()));
  impl->sensor = sensor;
  impl->attach();
  return LidarStream(std::move(impl));
}

LidarStream::LidarStream(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LidarStream::LidarStream(LidarStream&&) noexcept = default;
LidarStream& LidarStream::operator=(LidarStream&&) noexcept = default;
LidarStream::~LidarStream() = default;

PushResult LidarStream::push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns,
                             std::int64_t time_reference_ns) noexcept {
  PushResult result = impl_->assembler.push(payload, host_receive_ns, time_reference_ns);
  if (result.frame) impl_->publish(*result.frame);
  return result;
}

bool LidarStream::push_position(std::span<const std::uint8_t> payload) noexcept {
  const auto report = parse_position_packet(payload);
  if (!report) {
    ++impl_->published.position_malformed;
    return false;
  }
  ++impl_->published.position_packets;
  TimeSync sync = time_sync_of(*report);
  if (sync.text == impl_->sync.text && sync.base == impl_->sync.base) return true;
  impl_->sync = std::move(sync);
  if (impl_->sensor) {
    // Position packets come about once a second; the description changes only with the state.
    impl_->sensor->time_base = impl_->sync.base;
    impl_->sensor->time_sync = impl_->sync.text;
    (void)impl_->writer.set_sensor_info(*impl_->sensor);
  }
  return true;
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
const TimeSync& LidarStream::time_sync() const noexcept { return impl_->sync; }
Writer& LidarStream::writer() noexcept { return impl_->writer; }

std::string LidarStream::describe_counters(bool machine) const {
  const AssemblerCounters& c = impl_->assembler.counters();
  const PublishCounters& p = impl_->published;
  std::ostringstream out;
  if (machine) {
    std::string sync = impl_->sync.text;
    for (char& ch : sync) ch = (ch == ' ' || ch == ',') ? '_' : ch;
    out << "frames=" << p.frames << " packets=" << c.packets << " lost=" << c.lost_packets
        << " malformed=" << c.malformed << " wrong_model=" << c.wrong_model << " points=" << p.points
        << " partial_frames=" << p.partial_frames << " dropped_points=" << c.dropped_points
        << " publish_failures=" << p.failed << " position_packets=" << p.position_packets
        << " time_sync=" << sync;
  } else {
    out << "frames " << p.frames << " packets " << c.packets << " lost " << c.lost_packets << " malformed "
        << c.malformed << " wrong-model " << c.wrong_model << " points/frame " << impl_->last_points;
    if (c.dropped_points != 0) out << " dropped-points " << c.dropped_points;
    if (const auto mode = impl_->assembler.return_mode()) out << " " << to_string(*mode);
    out << " time " << impl_->sync.text;
  }
  return out.str();
}

std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
  Packet packet;
  if (Packet::parse(payload, model, packet) != PacketError::none) return std::nullopt;
  return packet.dual() ? 2U : 1U;
}

}  // namespace sim::velodyne
