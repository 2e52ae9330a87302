// SPDX-License-Identifier: Apache-2.0
// PointStream: what every LiDAR family's LidarStream is (Hesai, Velodyne, Ouster): the SIM
// point writer with the family's frame assembler decoding straight into its loaned slot, and the
// verbs every caller uses (push, finish, reset, the stamp offset, the counters, the clock
// check, describe_counters). A family's stream derives from it and adds only what is its own
// (Velodyne's position packets, Ouster's IMU and metadata, Hesai's model and cut time):
//
//   struct StreamFamily { using Assembler = FrameAssembler; using Counters = PublishCounters;
//                         struct State {}; static constexpr bool whole_at_finish = false;
//                         static void describe(std::ostream&, bool, const lidar::StreamPipeline<StreamFamily>&); };
//   class LidarStream : public lidar::PointStream<StreamFamily> { static Expected<LidarStream> create(…); … };
//
// Every verb is inline over the family's types: a packet costs the assembler's push and, when
// it completes a frame, the commit; no virtual call, no allocation.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <utility>

#include "sim/lidar/frame_publisher.hpp"

namespace sim::lidar {

// What a family gives PointStream<Family>:
//   using Assembler   its FrameAssembler: push(payload, host_receive_ns, more…) -> PushResult,
//                     finish(), reset(), set_output(span), options().emit_partial_frames, counters()
//                     with packets, lost_packets and malformed
//   using Counters    its PublishCounters (lidar::PublishCounters, or one deriving from it)
//   struct State      what its stream keeps beside the pipeline (an empty struct: nothing)
//   whole_at_finish   whether the frame in progress at the end of input can be whole (Ouster's
//                     column window can; a revolution is whole only when the next one begins,
//                     so without emit_partial_frames Hesai and Velodyne drop it)
//   describe(out, machine, pipeline)   the family's counters after "frames … malformed …"
template <class Family>
struct StreamPipeline : PointPipeline<typename Family::Assembler, typename Family::Counters> {
  using PointPipeline<typename Family::Assembler, typename Family::Counters>::PointPipeline;
  typename Family::State state;
};

template <class Family>
class PointStream {
 public:
  using Pipeline = StreamPipeline<Family>;
  using Counters = typename Family::Counters;

  PointStream(PointStream&&) noexcept = default;
  PointStream& operator=(PointStream&&) noexcept = default;
  PointStream(const PointStream&) = delete;
  PointStream& operator=(const PointStream&) = delete;
  ~PointStream() = default;

  // Decodes one data packet (`more`: the family's further arguments, e.g. Velodyne's time
  // reference); publishes the frame it completes, if any (PushResult::frame).
  template <class... More>
  auto push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns, More... more) noexcept {
    return pipeline_->push(payload, host_receive_ns, more...);
  }
  // End of input: publishes the frame in progress when it may be published (partial frames
  // enabled, or it is whole) and returns it.
  auto finish() noexcept {
    if constexpr (!Family::whole_at_finish) {
      if (!pipeline_->assembler.options().emit_partial_frames) {
        pipeline_->assembler.reset();
        return decltype(pipeline_->finish()){};
      }
    }
    return pipeline_->finish();
  }
  // Forgets the frame in progress (a capture loops, a sensor was silent).
  void reset() noexcept { pipeline_->assembler.reset(); }
  // Added to every published stamp from now on: a replay keeps stamps increasing across loops
  // of its capture, or moves them to the present (--restamp). Zero (the default) publishes the
  // sensor's own time, as the live drivers do.
  void set_stamp_offset(std::int64_t offset_ns) noexcept { pipeline_->frames.set_stamp_offset(offset_ns); }
  std::int64_t stamp_offset() const noexcept { return pipeline_->frames.stamp_offset(); }

  const auto& counters() const noexcept { return pipeline_->assembler.counters(); }  // the assembler's
  const Counters& published() const noexcept { return pipeline_->published; }
  std::uint64_t max_points() const noexcept { return pipeline_->frames.max_points(); }
  Writer& writer() noexcept { return pipeline_->frames.writer(); }
  // The clock check: the caller adds each packet's sensor time (PushResult::packet_ns) with its
  // arrival (live: the datagram's receive stamp; a replay: the record's capture time) and
  // ticks it; it judges and writes the stream's clock about once a second (`at_once`: now).
  timing::ClockReporter& clock() noexcept { return pipeline_->clock; }
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false) {
    return pipeline_->tick_clock(now_realtime_ns, at_once);
  }

  // "frames 12 packets 3600 lost 0 malformed 0 …" for status lines; `key=value` pairs with
  // `machine` ("frames=12 packets=3600 …") for summaries, whose keys scripts parse.
  std::string describe_counters(bool machine = false) const {
    const auto& c = pipeline_->assembler.counters();
    std::ostringstream out;
    describe_frames(out, machine, pipeline_->published.frames, c.packets, c.lost_packets, c.malformed);
    Family::describe(out, machine, *pipeline_);
    return out.str();
  }

 protected:
  // The pipeline lives on the heap and never moves (the publisher's loan points at its writer).
  explicit PointStream(std::unique_ptr<Pipeline> pipeline) noexcept : pipeline_(std::move(pipeline)) {}
  static std::unique_ptr<Pipeline> make_pipeline(Writer writer, typename Family::Assembler assembler) {
    return std::make_unique<Pipeline>(std::move(writer), std::move(assembler));
  }

  Pipeline& pipeline() noexcept { return *pipeline_; }
  const Pipeline& pipeline() const noexcept { return *pipeline_; }

 private:
  std::unique_ptr<Pipeline> pipeline_;
};

}  // namespace sim::lidar
