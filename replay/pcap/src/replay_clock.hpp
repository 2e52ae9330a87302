// SPDX-License-Identifier: Apache-2.0
// The clock check of a replayed packet, the same for every family: recorded stamps are measured
// against the capture's time of their record (the recording host's clock), restamped ones
// (--restamp) against this host's clock now, as a live driver's would be.
#pragma once

#include <cstdint>
#include <optional>

#include "sim/clock.hpp"
#include "sim/timing/clock_reporter.hpp"

namespace sim::pcap {

// `stream`: a family's LidarStream (clock(), stamp_offset(), tick_clock()).
template <class Stream>
void clock_replayed_packet(Stream& stream, const std::optional<std::int64_t>& sensor_ns,
                           std::int64_t capture_ns, std::int64_t now_ns) {
  if (sensor_ns) {
    if (stream.clock().base() == timing::ClockBase::restamped) {
      stream.clock().add(saturating_add_ns(*sensor_ns, stream.stamp_offset()), now_ns);
    } else {
      stream.clock().add(*sensor_ns, capture_ns);
    }
  }
  stream.tick_clock(now_ns);
}

// The end of the replay: the last judgement, so that even a capture shorter than the first tick
// leaves its verdict in the stream.
template <class Stream>
void clock_at_end(Stream& stream) {
  stream.tick_clock(realtime_ns(), true);
}

}  // namespace sim::pcap
