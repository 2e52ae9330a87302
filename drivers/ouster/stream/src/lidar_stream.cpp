// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/lidar_stream.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <string_view>
#include <ostream>
#include <utility>

#include "sim/clock.hpp"

namespace sim::ouster {

ImuSample to_sample(const ImuPacket& packet) noexcept {
  constexpr float g = 9.80665F;
  constexpr float radians_per_degree = static_cast<float>(std::numbers::pi / 180.0);
  ImuSample s;
  s.stamp_ns = static_cast<std::int64_t>(packet.accel_ns);
  s.gyro_stamp_ns = static_cast<std::int64_t>(packet.gyro_ns);
  for (unsigned i = 0; i < 3; ++i) {
    s.linear_acceleration[i] = packet.acceleration_g[i] * g;
    s.angular_velocity[i] = packet.angular_velocity_dps[i] * radians_per_degree;
  }
  return s;
}

std::string default_imu_stream(const std::string& points_stream) { return points_stream + ".imu"; }

void describe_live_clock(SensorInfo& info, const Metadata& metadata) {
  const std::string& mode = metadata.timestamp_mode;
  if (mode == "TIME_FROM_INTERNAL_OSC") {
    info.time_base = TimeBase::sensor_free_running;
    info.time_sync = "the sensor's own clock from power-on (timestamp_mode TIME_FROM_INTERNAL_OSC)";
  } else if (mode == "TIME_FROM_PTP_1588" || mode == "TIME_FROM_SYNC_PULSE_IN") {
    info.time_base = TimeBase::sensor_synchronized;
    info.time_sync = (mode == "TIME_FROM_PTP_1588" ? "PTP" : "the sync pulse input") +
                     std::string(" (timestamp_mode ") + mode + "; whether it is locked is not read)";
  } else {
    // Another mode (a later firmware's) is named as the metadata gives it, made fit for the
    // description (64 bytes at most, control characters as '?').
    info.time_base = TimeBase::unknown;
    info.time_sync = mode.empty() ? "the sensor's clock; the metadata does not give its timestamp_mode"
                                  : "the sensor's clock, timestamp_mode " + sensor_text(mode, 64) +
                                        " (not known to this driver)";
  }
}

namespace {

SensorInfo describe_sensor(const LidarStreamConfig& config, const Metadata& m) {
  SensorInfo info = *config.sensor;
  info.identity.vendor = "Ouster";
  info.identity.model = sensor_text(m.prod_line, SensorInfo::kMaxName);
  info.identity.serial = sensor_text(m.serial, SensorInfo::kMaxName);
  info.identity.firmware = sensor_text(m.firmware, SensorInfo::kMaxName);
  info.calibration_source = sensor_text(config.metadata_source, SensorInfo::kMaxSource);
  info.point_time = PointTime::after_frame_stamp;
  return info;
}

// The rotation and translation of a 4 × 4 row-major transform in millimetres, as a mounting
// (metres, unit quaternion x, y, z, w). The quaternion comes from the matrix's largest diagonal
// term (Shepperd's method: no division by a small number) and is normalised, so a metadata
// matrix a little off orthonormal still gives a unit rotation.
Mounting mounting_of(const std::array<double, 16>& t) {
  auto r = [&t](unsigned row, unsigned col) { return t[4 * row + col]; };
  const double trace = r(0, 0) + r(1, 1) + r(2, 2);
  std::array<double, 4> q;  // x, y, z, w
  if (trace >= r(0, 0) && trace >= r(1, 1) && trace >= r(2, 2)) {
    const double s = 2 * std::sqrt(1 + trace);
    q = {(r(2, 1) - r(1, 2)) / s, (r(0, 2) - r(2, 0)) / s, (r(1, 0) - r(0, 1)) / s, s / 4};
  } else if (r(0, 0) >= r(1, 1) && r(0, 0) >= r(2, 2)) {
    const double s = 2 * std::sqrt(1 + r(0, 0) - r(1, 1) - r(2, 2));
    q = {s / 4, (r(0, 1) + r(1, 0)) / s, (r(0, 2) + r(2, 0)) / s, (r(2, 1) - r(1, 2)) / s};
  } else if (r(1, 1) >= r(2, 2)) {
    const double s = 2 * std::sqrt(1 + r(1, 1) - r(0, 0) - r(2, 2));
    q = {(r(0, 1) + r(1, 0)) / s, s / 4, (r(1, 2) + r(2, 1)) / s, (r(0, 2) - r(2, 0)) / s};
  } else {
    const double s = 2 * std::sqrt(1 + r(2, 2) - r(0, 0) - r(1, 1));
    q = {(r(0, 2) + r(2, 0)) / s, (r(1, 2) + r(2, 1)) / s, s / 4, (r(1, 0) - r(0, 1)) / s};
  }
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  Mounting m;
  m.translation = {t[3] / 1000.0, t[7] / 1000.0, t[11] / 1000.0};
  m.rotation = {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
  return m;
}

// The IMU's samples are in the IMU's own frame, which the metadata's imu_to_sensor_transform
// places in the sensor frame the points are in (ouster-ros: os_imu under os_sensor). So the IMU
// stream is "<points' frame>_imu", mounted on the points' frame by that transform.
SensorInfo describe_imu(const SensorInfo& points, const Metadata& m) {
  constexpr std::string_view suffix = "_imu";
  SensorInfo info = points;
  info.parent_frame = points.frame_id;
  info.frame_id = points.frame_id.substr(0, SensorInfo::kMaxName - suffix.size()) + std::string(suffix);
  info.mounting = mounting_of(m.imu_to_sensor);
  info.point_time = PointTime::none;
  return info;
}

}  // namespace

Expected<LidarStream> LidarStream::create(const LidarStreamConfig& config, const Metadata& metadata) {
  auto assembler = FrameAssembler::create(metadata, config.assembler);
  if (!assembler) return assembler.error();

  StreamSpec spec = lidar::point_stream_spec(config, assembler->max_points());
  if (config.sensor) spec.sensor = describe_sensor(config, metadata);
  auto writer = Writer::create(spec);
  if (!writer) return writer.error();

  std::optional<Writer> imu;
  if (!config.imu_stream.empty()) {
    StreamSpec imu_spec;
    imu_spec.name = config.imu_stream;
    imu_spec.capacity = sizeof(ImuSample);
    imu_spec.layout = Layout::raw();
    imu_spec.checksum = config.checksum;
    imu_spec.heartbeat_period = config.heartbeat_period;
    if (spec.sensor) imu_spec.sensor = describe_imu(*spec.sensor, metadata);
    auto imu_writer = Writer::create(imu_spec);
    if (!imu_writer) return imu_writer.error();
    imu.emplace(std::move(imu_writer.value()));
  }
  auto pipeline = make_pipeline(std::move(writer.value()), std::move(assembler.value()));
  pipeline->state.imu = std::move(imu);
  return LidarStream(std::move(pipeline));
}

bool LidarStream::push_imu(std::span<const std::uint8_t> payload) noexcept {
  Pipeline& p = pipeline();
  const auto packet = parse_imu(payload);
  if (!packet) {
    ++p.published.imu_malformed;
    return false;
  }
  ++p.published.imu_samples;
  if (p.state.imu) {
    ImuSample sample = to_sample(*packet);
    sample.stamp_ns = saturating_add_ns(sample.stamp_ns, p.frames.stamp_offset());
    sample.gyro_stamp_ns = saturating_add_ns(sample.gyro_stamp_ns, p.frames.stamp_offset());
    (void)p.state.imu->write(std::span<const ImuSample>(&sample, 1), sample.stamp_ns);
  }
  return true;
}

std::string LidarStream::mismatch_problem() const {
  const AssemblerCounters& c = pipeline().assembler.counters();
  const Metadata& m = pipeline().assembler.metadata();
  const auto rejected = [&](PacketError e) { return c.rejected[static_cast<unsigned>(e)]; };
  if (rejected(PacketError::wrong_size) != 0) return describe_mismatch(c.last_rejected_size, m.format);
  if (rejected(PacketError::bad_measurement_id) != 0) {
    return "lidar packets hold column indices beyond the metadata's " + std::to_string(m.columns()) +
           " columns per frame: the lidar mode changed; give the sensor's current metadata";
  }
  if (rejected(PacketError::init_id_mismatch) != 0) {
    return "lidar packets carry another initialization id than the metadata's (" +
           std::to_string(m.init_id) + "): the sensor was reconfigured or restarted since; fetch "
           "its metadata again";
  }
  if (rejected(PacketError::not_lidar) != 0) {
    return "datagrams of the lidar packet size arrive with a packet type other than lidar; check "
           "the port";
  }
  return {};
}

void StreamFamily::describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& pipeline) {
  const AssemblerCounters& c = pipeline.assembler.counters();
  const PublishCounters& p = pipeline.published;
  out << (machine ? " imu=" : " imu ") << p.imu_samples;
  if (machine) {
    out << " points=" << p.points << " partial_frames=" << p.partial_frames
        << " partial_frames_dropped=" << c.partial_frames_dropped << " late_packets=" << c.late_packets
        << " invalid_columns=" << c.invalid_columns << " duplicate_columns=" << c.duplicate_columns
        << " dropped_points=" << c.dropped_points << " publish_failures=" << p.failed
        << " imu_malformed=" << p.imu_malformed;
    for (unsigned e = 1; e < packet_error_count; ++e) {
      std::string name = to_string(static_cast<PacketError>(e));
      for (char& ch : name) ch = ch == ' ' ? '_' : ch;
      out << " " << name << "=" << c.rejected[e];
    }
  } else {
    out << " points/frame " << pipeline.frames.last_points();
    if (p.imu_malformed != 0) out << " imu-malformed " << p.imu_malformed;
    if (c.invalid_columns != 0) out << " invalid-columns " << c.invalid_columns;
  }
}

}  // namespace sim::ouster
