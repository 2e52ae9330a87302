// SPDX-License-Identifier: Apache-2.0
// FramePublisher: the SIM end every LiDAR stream shares (Hesai, Velodyne, Ouster). It owns the
// point writer and its loaned slot, which the family's frame assembler decodes into (points go
// straight to shared memory), commits a finished frame with the stamp offset and counts what
// was published. No allocation per frame.
//
//   auto writer = Writer::create(sim::lidar::point_stream_spec(config, max_points));
//   lidar::PointPipeline<FrameAssembler, PublishCounters> pipeline(std::move(writer), assembler);
//   pipeline.push(payload, host_receive_ns);   // decodes; publishes the frame it completes
// (a family's LidarStream holds one through lidar::PointStream, point_stream.hpp)
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <iosfwd>
#include <string>
#include <utility>

#include "sim/clock.hpp"
#include "sim/lidar/completed_frame.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar_point.hpp"
#include "sim/writer.hpp"

namespace sim::lidar {

// What a LiDAR stream published; a family's PublishCounters adds its own.
struct PublishCounters {
  std::uint64_t frames = 0;          // frames committed to the SIM stream
  std::uint64_t points = 0;          // points in those frames
  std::uint64_t partial_frames = 0;  // of those, frames that were not a whole revolution
  std::uint64_t failed = 0;          // commits the writer refused (cannot happen when sized
                                     // right; counted rather than assumed)
};

// The SIM stream of a family's config (its stream, checksum, lock_memory and heartbeat_period)
// holding `max_points` LidarPoints a frame.
template <class Config>
StreamSpec point_stream_spec(const Config& config, std::uint64_t max_points) {
  StreamSpec spec;
  spec.name = config.stream;
  spec.layout = Layout::of(PointLayout::of(PointType::lidar_point, max_points));
  spec.checksum = config.checksum;
  spec.lock_memory = config.lock_memory;
  spec.heartbeat_period = config.heartbeat_period;
  return spec;
}

// "file:///abs/path/unit.csv", cut to SensorInfo::kMaxSource: a calibration file as the
// description's calibration source.
std::string file_source(const std::filesystem::path& file);

// Writes "frames 12 packets 3600 lost 0 malformed 0", or with `machine` "frames=12 packets=3600
// lost=0 malformed=0": how every LiDAR status line and summary begins.
void describe_frames(std::ostream& out, bool machine, std::uint64_t frames, std::uint64_t packets,
                     std::uint64_t lost, std::uint64_t malformed);

class FramePublisher {
 public:
  // Lends the writer's back slot at once. `counters` (the family's, which may hold more) must
  // outlive the publisher. The loan points at the writer: the publisher never moves, so it
  // lives in a family's heap-held Impl.
  FramePublisher(Writer writer, PublishCounters& counters) noexcept;
  FramePublisher(const FramePublisher&) = delete;
  FramePublisher& operator=(const FramePublisher&) = delete;

  // The loaned slot, for the assembler's output.
  std::span<LidarPoint> slot() const noexcept;
  // Commits the first `point_count` points of the slot as a frame stamped `stamp_ns` plus the
  // stamp offset, counts it, and returns the next slot (give it to the assembler before the
  // next packet).
  std::span<LidarPoint> publish(std::size_t point_count, std::int64_t stamp_ns, std::int64_t host_receive_ns,
                                bool whole) noexcept {
    return publish_stamped(point_count, saturating_add_ns(stamp_ns, stamp_offset_ns_), host_receive_ns, whole);
  }
  // The same with the stamp as published (the offset already applied, or another clock's).
  std::span<LidarPoint> publish_stamped(std::size_t point_count, std::int64_t stamp_ns,
                                        std::int64_t host_receive_ns, bool whole) noexcept;

  // Added to every published stamp from now on: a replay keeps stamps increasing across loops
  // of its capture, or moves them to the present (--restamp). Zero (the default) publishes the
  // sensor's own time, as the live drivers do.
  void set_stamp_offset(std::int64_t offset_ns) noexcept { stamp_offset_ns_ = offset_ns; }
  std::int64_t stamp_offset() const noexcept { return stamp_offset_ns_; }
  std::size_t last_points() const noexcept { return last_points_; }  // in the last frame
  std::uint64_t max_points() const noexcept { return writer_.layout().points.max_points; }
  Writer& writer() noexcept { return writer_; }

 private:
  void lend() noexcept;

  Writer writer_;
  Loan loan_;
  PublishCounters& counters_;
  std::size_t last_points_ = 0;
  std::int64_t stamp_offset_ns_ = 0;
};

// A family's FrameAssembler decoding straight into a FramePublisher's slot: what every
// LidarStream holds (lidar::StreamPipeline, point_stream.hpp). Lives on the heap and never moves (the publisher's loan points at
// its writer). `Counters` is the family's PublishCounters.
template <class Assembler, class Counters = PublishCounters>
struct PointPipeline {
  PointPipeline(Writer writer, Assembler a)
      : frames(std::move(writer), published), assembler(std::move(a)) {
    assembler.set_output(frames.slot());
  }
  PointPipeline(const PointPipeline&) = delete;
  PointPipeline& operator=(const PointPipeline&) = delete;

  // One payload (the assembler's push arguments); publishes the frame it completes.
  template <class... Args>
  auto push(Args... args) noexcept {
    auto result = assembler.push(args...);
    if (result.frame) publish(*result.frame);
    return result;
  }
  // End of input: publishes the frame in progress, when the assembler gives one.
  auto finish() noexcept {
    auto frame = assembler.finish();
    if (frame) publish(*frame);
    return frame;
  }

  // Judges the stream's clock about once a second (`now_realtime_ns`): see ClockReporter.
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false) {
    return clock.tick(frames.writer(), now_realtime_ns, at_once);
  }

  Counters published;  // before `frames`, which counts into it
  FramePublisher frames;
  Assembler assembler;
  timing::ClockReporter clock;  // the caller adds each packet's sensor time with its arrival

 private:
  // Every family's frame is a lidar::CompletedFrame, whatever it adds.
  void publish(const CompletedFrame& f) noexcept {
    // The sensor's stamp, or with --stamp-fallback its arrival while the sensor's clock is in error.
    const std::int64_t stamp =
        clock.frame_stamp(frames.writer(), saturating_add_ns(f.stamp_ns, frames.stamp_offset()), f.host_receive_ns);
    assembler.set_output(frames.publish_stamped(f.point_count, stamp, f.host_receive_ns, f.whole));
  }
};

}  // namespace sim::lidar
