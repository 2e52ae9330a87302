// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/lidar_stream.hpp"

#include <algorithm>
#include <sstream>
#include <utility>

#include "sim/layout.hpp"

namespace sim::unitree {

std::string default_imu_stream(std::string_view points_stream) {
  return std::string(points_stream) + ".imu";
}

timing::ClockBase stream_clock_base(const DecoderOptions& options, timing::ClockBase sensor_base) noexcept {
  const bool sensor_stamps = options.model == Model::l2 && options.time_source == TimeSource::sensor;
  return sensor_stamps ? sensor_base : timing::ClockBase::restamped;
}

SensorInfo describe_sensor(SensorInfo info, const DecoderOptions& options) {
  info.identity.vendor = "Unitree";
  info.identity.model = to_string(options.model);
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

// The Decoder's sink: each scan goes into the FramePublisher's loaned slot and is committed when
// the decoder completes it. Lives on the heap and never moves (the publisher's loan points at its
// writer, the decoder at this sink).
struct LidarStream::Impl final : ScanSink {
  Impl(Writer points, std::optional<Writer> imu, const LidarStreamConfig& config)
      : frames(std::move(points), published), imu_writer(std::move(imu)),
        publish_gate(config.publish_gate), decoder(config.decoder, *this) {
    clock.set_base(stream_clock_base(config.decoder, config.sensor_clock_base));
  }

  std::span<LidarPoint> begin_scan() override {
    // The slot lent since the last commit; a scan abandoned before (a reset, a 2D packet) gave
    // nothing back, so the next one simply writes over it.
    const std::span<LidarPoint> slot = frames.slot();
    return slot.first(std::min<std::size_t>(slot.size(), frames.max_points()));
  }
  void end_scan(std::size_t points, std::int64_t stamp_ns, std::int64_t receive_ns) override {
    if (publish_gate) {
      const std::optional<std::int64_t> stamp = publish_gate();
      if (!stamp) return;  // dropped: the slot stays lent for the next scan
      stamp_ns = *stamp;
    }
    // The stamp offset is the decoder's (it moves the L2's own stamps only, IMU samples too).
    const std::int64_t stamp = clock.frame_stamp(frames.writer(), stamp_ns, receive_ns);
    frames.publish_stamped(points, stamp, receive_ns, true);
    ++frames_in_push;
  }
  void imu(const ImuSample& sample) override {
    if (!imu_writer) return;
    if (imu_writer->write(std::span<const ImuSample>(&sample, 1), sample.stamp_ns) == WriteStatus::ok) {
      ++published.imu_samples;
    } else {
      ++published.imu_failed;
    }
  }
  void packet_time(std::int64_t stamp_ns, std::int64_t host_ns) override { clock.add(stamp_ns, host_ns); }

  PublishCounters published;  // before `frames`, which counts into it
  lidar::FramePublisher frames;
  timing::ClockReporter clock;
  std::optional<Writer> imu_writer;  // its own stream, one frame per sample
  std::function<std::optional<std::int64_t>()> publish_gate;
  std::size_t frames_in_push = 0;
  Decoder decoder;  // last: it holds this sink
};

namespace {

StreamSpec imu_stream_spec(const LidarStreamConfig& config, const std::optional<SensorInfo>& points) {
  StreamSpec spec;
  spec.name = config.imu_stream;
  spec.capacity = sizeof(ImuSample);
  spec.layout = Layout::raw();
  spec.checksum = config.checksum;
  spec.lock_memory = config.lock_memory;
  spec.heartbeat_period = config.heartbeat_period;
  if (points) {
    spec.sensor = points;
    spec.sensor->point_time = PointTime::none;
  }
  return spec;
}

}  // namespace

Expected<LidarStream> LidarStream::create(const LidarStreamConfig& config) {
  StreamSpec spec = lidar::point_stream_spec(config, Decoder::max_points_per_scan(config.decoder));
  if (config.sensor) spec.sensor = describe_sensor(*config.sensor, config.decoder);
  auto points = Writer::create(spec);
  if (!points) return points.error();
  std::optional<Writer> imu;
  if (!config.imu_stream.empty()) {
    auto imu_writer = Writer::create(imu_stream_spec(config, spec.sensor));
    if (!imu_writer) return imu_writer.error();
    imu.emplace(std::move(imu_writer.value()));
  }
  return LidarStream(std::make_unique<Impl>(std::move(points.value()), std::move(imu), config));
}

LidarStream::LidarStream(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LidarStream::LidarStream(LidarStream&&) noexcept = default;
LidarStream& LidarStream::operator=(LidarStream&&) noexcept = default;
LidarStream::~LidarStream() = default;

std::size_t LidarStream::push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept {
  impl_->frames_in_push = 0;
  impl_->decoder.push(payload, host_receive_ns);
  return impl_->frames_in_push;
}

void LidarStream::finish() noexcept { impl_->decoder.finish(); }
void LidarStream::reset() noexcept { impl_->decoder.reset(); }
void LidarStream::set_stamp_offset(std::int64_t offset_ns) noexcept { impl_->decoder.set_stamp_offset(offset_ns); }
std::int64_t LidarStream::stamp_offset() const noexcept { return impl_->decoder.stamp_offset(); }

Model LidarStream::model() const noexcept { return impl_->decoder.options().model; }
const DecoderOptions& LidarStream::options() const noexcept { return impl_->decoder.options(); }
DecoderCounters LidarStream::counters() const noexcept { return impl_->decoder.counters(); }
const PublishCounters& LidarStream::published() const noexcept { return impl_->published; }
std::uint64_t LidarStream::max_points() const noexcept { return impl_->frames.max_points(); }
Writer& LidarStream::writer() noexcept { return impl_->frames.writer(); }
timing::ClockReporter& LidarStream::clock() noexcept { return impl_->clock; }

std::optional<ClockStatus> LidarStream::tick_clock(std::int64_t now_realtime_ns, bool at_once) {
  std::optional<ClockStatus> clock = impl_->clock.tick(impl_->frames.writer(), now_realtime_ns, at_once);
  // The IMU samples come from the same clock: the same record.
  if (clock && impl_->imu_writer) timing::write_clock(*impl_->imu_writer, *clock);
  return clock;
}

std::string LidarStream::describe_counters(bool machine) const {
  const DecoderCounters c = impl_->decoder.counters();
  const PublishCounters& p = impl_->published;
  const FramerCounters& f = c.framing;
  std::ostringstream out;
  lidar::describe_frames(out, machine, p.frames, f.packets, c.lost_packets, c.malformed);
  if (machine) {
    // frames, packets, imu and failed are the keys sim_replay_pcap's Unitree summary always had.
    out << " imu=" << p.imu_samples << " failed=" << (p.failed + p.imu_failed) << " points=" << p.points
        << " partial_frames=" << p.partial_frames << " dropped_points=" << c.dropped_points
        << " bad_crc=" << f.bad_crc << " truncated=" << f.truncated << " resyncs=" << f.resyncs
        << " bad_header=" << f.wrong_header << " unpaired=" << c.unpaired << " ignored=" << c.ignored;
    return out.str();
  }
  out << " imu " << p.imu_samples << " points/frame " << impl_->frames.last_points();
  // What went wrong on the wire, only once it did.
  const auto problem = [&out](const char* name, std::uint64_t count) {
    if (count != 0) out << ' ' << name << ' ' << count;
  };
  problem("bad-crc", f.bad_crc);
  problem("truncated", f.truncated);
  problem("resyncs", f.resyncs);
  problem("bad-header", f.wrong_header);
  problem("unpaired", c.unpaired);
  problem("dropped-points", c.dropped_points);
  problem("publish-failures", p.failed + p.imu_failed);
  return out.str();
}

}  // namespace sim::unitree
