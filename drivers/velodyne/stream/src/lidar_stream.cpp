// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/lidar_stream.hpp"

#include <mutex>
#include <ostream>
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

  auto pipeline = make_pipeline(std::move(writer.value()), std::move(assembler.value()));
  StreamFamily::State& state = pipeline->state;
  state.sensor = sensor;
  state.stamp_clock = config.stamp_clock;
  state.reported.set(initial_clock(config.stamp_clock));
  if (config.sensor) state.caller_time_sync = config.sensor->time_sync;
  return LidarStream(std::move(pipeline));
}

bool LidarStream::push_position(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept {
  Pipeline& p = pipeline();
  StreamFamily::State& state = p.state;
  const auto report = parse_position_packet(payload, model());
  if (!report) {
    ++p.published.position_malformed;
    return false;
  }
  ++p.published.position_packets;
  const std::int64_t arrival = host_receive_ns != 0 ? host_receive_ns : realtime_ns();
  state.reported.set(stream_clock(clock_status_of(*report, arrival), state.stamp_clock));
  TimeSync sync = time_sync_of(*report);
  if (sync.text == state.sync.text && sync.base == state.sync.base) return true;
  state.sync = std::move(sync);
  if (state.sensor && state.stamp_clock != StampClock::restamped) {
    // Position packets come about once a second; the description changes only with the state.
    describe_time_sync(*state.sensor, state.sync, state.stamp_clock, state.caller_time_sync);
    (void)p.frames.writer().set_sensor_info(*state.sensor);
  }
  return true;
}

void StreamFamily::describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& pipeline) {
  const AssemblerCounters& c = pipeline.assembler.counters();
  const PublishCounters& p = pipeline.published;
  if (machine) {
    std::string sync = pipeline.state.sync.text;
    for (char& ch : sync) ch = (ch == ' ' || ch == ',') ? '_' : ch;
    out << " wrong_model=" << c.wrong_model << " points=" << p.points
        << " partial_frames=" << p.partial_frames << " dropped_points=" << c.dropped_points
        << " publish_failures=" << p.failed << " position_packets=" << p.position_packets
        << " time_sync=" << sync;
  } else {
    out << " wrong-model " << c.wrong_model << " points/frame " << pipeline.frames.last_points();
    if (c.dropped_points != 0) out << " dropped-points " << c.dropped_points;
    if (const auto mode = pipeline.assembler.return_mode()) out << " " << to_string(*mode);
    out << " time " << pipeline.state.sync.text;
  }
}

std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
  Packet packet;
  if (Packet::parse(payload, model, packet) != PacketError::none) return std::nullopt;
  return packet.dual() ? 2U : 1U;
}

}  // namespace sim::velodyne
