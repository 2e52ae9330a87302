// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/sim_sink.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "sim/layout.hpp"

namespace sim::unitree {

std::string default_imu_stream(std::string_view points_stream) {
  return std::string(points_stream) + ".imu";
}

lidar::ClockBase stream_clock_base(const DecoderOptions& options, lidar::ClockBase sensor_base) noexcept {
  const bool sensor_stamps = options.model == Model::l2 && options.time_source == TimeSource::sensor;
  return sensor_stamps ? sensor_base : lidar::ClockBase::restamped;
}

SensorInfo describe_sensor(SensorInfo info, const DecoderOptions& options) {
  info.identity.vendor = "Unitree";
  info.identity.model = options.model == Model::l1 ? "L1" : "L2";
  info.point_time = PointTime::after_frame_stamp;
  // A caller that knows better (a replay: the recording host's clock) has set time_sync already.
  if (options.time_source == TimeSource::sensor) {
    info.time_base = TimeBase::unknown;
    if (info.time_sync.empty()) info.time_sync = "the L2's own clock; its synchronisation is not reported";
  } else {
    info.time_base = TimeBase::host;
    if (info.time_sync.empty()) info.time_sync = "host receive time";
  }
  return info;
}

Expected<std::unique_ptr<SimScanSink>> SimScanSink::create(const SimSinkOptions& options) {
  StreamSpec points_spec;
  points_spec.name = options.points_stream;
  points_spec.layout = Layout::of(PointLayout::of(PointType::lidar_point, options.max_points));
  points_spec.checksum = options.checksum;
  // Readers can tell an idle driver (no data from the sensor) from a dead one.
  points_spec.heartbeat_period = std::chrono::milliseconds(500);
  points_spec.sensor = options.sensor;
  Expected<Writer> points = Writer::create(points_spec);
  if (!points) return points.error();

  std::optional<Writer> imu;
  if (!options.imu_stream.empty()) {
    StreamSpec imu_spec;
    imu_spec.name = options.imu_stream;
    imu_spec.capacity = sizeof(ImuSample);
    imu_spec.layout = Layout::raw();
    imu_spec.checksum = options.checksum;
    imu_spec.heartbeat_period = std::chrono::milliseconds(500);
    if (options.sensor) {
      imu_spec.sensor = options.sensor;
      imu_spec.sensor->point_time = PointTime::none;
    }
    Expected<Writer> imu_writer = Writer::create(imu_spec);
    if (!imu_writer) return imu_writer.error();
    imu.emplace(std::move(imu_writer.value()));
  }
  auto sink = std::unique_ptr<SimScanSink>(
      new SimScanSink(std::move(points.value()), std::move(imu), options.max_points));
  sink->clock_.set_base(options.clock_base);
  return sink;
}

std::optional<ClockStatus> SimScanSink::tick_clock(std::int64_t now_realtime_ns, bool at_once) {
  std::optional<ClockStatus> clock = clock_.tick(points_, now_realtime_ns, at_once);
  // The IMU packets come from the same clock: the same record.
  if (clock && imu_) lidar::write_clock(*imu_, *clock);
  return clock;
}

SimScanSink::SimScanSink(Writer points, std::optional<Writer> imu,
                         std::uint64_t max_points) noexcept
    : points_(std::move(points)), imu_(std::move(imu)), max_points_(max_points) {}

std::span<LidarPoint> SimScanSink::begin_scan() {
  loan_.reset();  // a scan begun and never ended gives its slot back first: one loan at a time
  loan_.emplace(points_.loan());
  const std::span<LidarPoint> slot = loan_->as<LidarPoint>();
  return slot.first(std::min<std::size_t>(slot.size(), max_points_));
}

void SimScanSink::end_scan(std::size_t points, std::int64_t stamp_ns, std::int64_t receive_ns) {
  if (!loan_) return;
  const WriteStatus status = std::move(*loan_).commit(points * sizeof(LidarPoint), stamp_ns, receive_ns);
  loan_.reset();
  if (status == WriteStatus::ok) {
    ++counters_.scans_published;
  } else {
    ++counters_.publish_failures;
  }
}

void SimScanSink::imu(const ImuSample& sample) {
  if (!imu_) return;
  if (imu_->write(std::span<const ImuSample>(&sample, 1), sample.stamp_ns) == WriteStatus::ok) {
    ++counters_.imu_published;
  } else {
    ++counters_.publish_failures;
  }
}

Expected<std::unique_ptr<UnitreeStream>> UnitreeStream::create(
    const UnitreeStreamOptions& options) {
  SimSinkOptions sink_options;
  sink_options.points_stream = options.points_stream;
  if (!options.no_imu) {
    sink_options.imu_stream = options.imu_stream.empty()
                                  ? default_imu_stream(options.points_stream)
                                  : options.imu_stream;
  }
  sink_options.max_points = Decoder::max_points_per_scan(options.decoder);
  sink_options.checksum = options.checksum;
  sink_options.clock_base = stream_clock_base(options.decoder, options.sensor_clock_base);
  if (options.sensor) sink_options.sensor = describe_sensor(*options.sensor, options.decoder);
  auto sink = SimScanSink::create(sink_options);
  if (!sink) return sink.error();
  return std::unique_ptr<UnitreeStream>(
      new UnitreeStream(std::move(sink.value()), options.decoder));
}

std::string UnitreeStream::status() const {
  return format_status(decoder_.counters(), sink_->counters());
}

std::string format_status(const DecoderCounters& d, const SimSinkCounters& s) {
  char line[400];
  std::snprintf(line, sizeof line,
                "scans %llu  points %llu  imu %llu  packets %llu | bad_crc %llu  truncated %llu  "
                "resyncs %llu  bad_header %llu  lost %llu  dropped_points %llu",
                static_cast<unsigned long long>(s.scans_published),
                static_cast<unsigned long long>(d.points),
                static_cast<unsigned long long>(s.imu_published),
                static_cast<unsigned long long>(d.framing.packets),
                static_cast<unsigned long long>(d.framing.bad_crc),
                static_cast<unsigned long long>(d.framing.truncated),
                static_cast<unsigned long long>(d.framing.resyncs),
                static_cast<unsigned long long>(d.framing.wrong_header),
                static_cast<unsigned long long>(d.lost_packets),
                static_cast<unsigned long long>(d.dropped_points));
  return line;
}

}  // namespace sim::unitree
