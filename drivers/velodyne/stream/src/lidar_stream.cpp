// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/lidar_stream.hpp"

#include <mutex>
#include <sstream>
#include <utility>

#include "sim/clock.hpp"
#include "sim/velodyne/position_clock.hpp"

namespace sim::velodyne {

namespace {

// "GPRMC valid", "GPRMC no fix", "GPGGA fix", "NMEA unreadable", "no GPRMC".
std::string nmea_text(const PositionReport& report) {
  if (report.has_gprmc) return report.gprmc_valid ? "GPRMC valid" : "GPRMC no fix";
  switch (report.nmea) {
    case NmeaStatus::fix: return "GPGGA fix";
    case NmeaStatus::no_fix: return "GPGGA no fix";
    case NmeaStatus::unreadable: return "NMEA unreadable";
    case NmeaStatus::none: break;
  }
  return "no GPRMC";
}

}  // namespace

TimeSync time_sync_of(const PositionReport& report) {
  TimeSync sync;
  const std::string gprmc = nmea_text(report);
  const bool pps_locked = report.pps == PpsState::locked;
  if (report.pps == PpsState::unknown) {
    sync.text = gprmc;  // HDL-32E/64E position packets carry no PPS state
    sync.base = report.nmea == NmeaStatus::fix ? TimeBase::sensor_synchronized : TimeBase::sensor_free_running;
  } else {
    sync.text = std::string("PPS ") + to_string(report.pps) + ", " + gprmc;
    sync.base = pps_locked ? TimeBase::sensor_synchronized : TimeBase::sensor_free_running;
  }
  return sync;
}

namespace {

// The clock record of the stamps `clock` says the stream publishes, before any position packet.
ClockStatus initial_clock(StampClock clock) {
  ClockStatus status;
  status.stamps = sim::StampClock::sensor;
  if (clock == StampClock::restamped) {
    status.source = ClockSource::host;
    status.stamps = sim::StampClock::host_arrival;
  }
  return status;
}

// `reported` (a position packet's clock) as a stream whose stamps are `clock` reports it: live as
// it is; a replay with the recorded stamps as a recording; a restamped replay as this host's
// clock, whatever the recorded packets say.
ClockStatus stream_clock(ClockStatus reported, StampClock clock) {
  switch (clock) {
    case StampClock::sensor_live: return reported;
    case StampClock::sensor_recorded:
      reported.source = ClockSource::replayed;
      if (!reported.problem.empty()) {
        reported.problem = ("as recorded: " + reported.problem).substr(0, ClockStatus::kMaxProblem);
      }
      return reported;
    case StampClock::restamped: {
      ClockStatus host = initial_clock(clock);
      host.reported_ns = reported.reported_ns;
      return host;
    }
  }
  return reported;
}

// What the position packets' state `sync` makes of the description's clock, as `clock` says;
// `caller_time_sync` is the time_sync the stream was created with.
void describe_time_sync(SensorInfo& info, const TimeSync& sync, StampClock clock,
                        const std::string& caller_time_sync) {
  switch (clock) {
    case StampClock::sensor_live:
      info.time_base = sync.base;
      info.time_sync = sync.text;
      return;
    case StampClock::sensor_recorded:
      info.time_base = sync.base;
      info.time_sync = sensor_text(caller_time_sync + "; as recorded: " + sync.text, SensorInfo::kMaxSource);
      return;
    case StampClock::restamped:
      return;  // the stamps are not the sensor's clock: the caller's words stand
  }
}

}  // namespace

struct LidarStream::Impl : lidar::PointPipeline<FrameAssembler, PublishCounters> {
  using PointPipeline::PointPipeline;
  std::optional<SensorInfo> sensor;  // the description, re-set when the time sync changes
  TimeSync sync;
  ReportedClock reported;  // what the position packets last said of the clock
  StampClock stamp_clock = StampClock::sensor_live;
  std::string caller_time_sync;  // LidarStreamConfig::sensor's, which sensor_recorded extends
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

  StreamSpec spec = lidar::point_stream_spec(config, frame_capacity(model, config.returns, config.min_rpm));
  std::optional<SensorInfo> sensor = config.sensor;
  if (sensor) {
    sensor->identity.vendor = "Velodyne";
    sensor->identity.model = std::string(to_string(model));
    sensor->calibration_source = lidar::file_source(config.calibration);
    sensor->point_time = PointTime::after_frame_stamp;
    describe_time_sync(*sensor, TimeSync{}, config.stamp_clock, config.sensor->time_sync);
    spec.sensor = sensor;
  }
  auto writer = Writer::create(spec);
  if (!writer) return writer.error();

  auto impl = std::make_unique<Impl>(std::move(writer.value()), std::move(assembler.value()));
  impl->sensor = sensor;
  impl->stamp_clock = config.stamp_clock;
  impl->reported.set(initial_clock(config.stamp_clock));
  if (config.sensor) impl->caller_time_sync = config.sensor->time_sync;
  return LidarStream(std::move(impl));
}

LidarStream::LidarStream(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LidarStream::LidarStream(LidarStream&&) noexcept = default;
LidarStream& LidarStream::operator=(LidarStream&&) noexcept = default;
LidarStream::~LidarStream() = default;

PushResult LidarStream::push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns,
                             std::int64_t time_reference_ns) noexcept {
  return impl_->push(payload, host_receive_ns, time_reference_ns);
}

bool LidarStream::push_position(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept {
  const auto report = parse_position_packet(payload, model());
  if (!report) {
    ++impl_->published.position_malformed;
    return false;
  }
  ++impl_->published.position_packets;
  const std::int64_t arrival = host_receive_ns != 0 ? host_receive_ns : realtime_ns();
  impl_->reported.set(stream_clock(clock_status_of(*report, arrival), impl_->stamp_clock));
  TimeSync sync = time_sync_of(*report);
  if (sync.text == impl_->sync.text && sync.base == impl_->sync.base) return true;
  impl_->sync = std::move(sync);
  if (impl_->sensor && impl_->stamp_clock != StampClock::restamped) {
    // Position packets come about once a second; the description changes only with the state.
    describe_time_sync(*impl_->sensor, impl_->sync, impl_->stamp_clock, impl_->caller_time_sync);
    (void)impl_->frames.writer().set_sensor_info(*impl_->sensor);
  }
  return true;
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
const TimeSync& LidarStream::time_sync() const noexcept { return impl_->sync; }
ReportedClock LidarStream::reported_clock() const { return impl_->reported; }
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
  if (machine) {
    std::string sync = impl_->sync.text;
    for (char& ch : sync) ch = (ch == ' ' || ch == ',') ? '_' : ch;
    out << " wrong_model=" << c.wrong_model << " points=" << p.points
        << " partial_frames=" << p.partial_frames << " dropped_points=" << c.dropped_points
        << " publish_failures=" << p.failed << " position_packets=" << p.position_packets
        << " time_sync=" << sync;
  } else {
    out << " wrong-model " << c.wrong_model << " points/frame " << impl_->frames.last_points();
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
