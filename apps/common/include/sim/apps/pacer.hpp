// SPDX-License-Identifier: Apache-2.0
// Paces a replay or a playback by the recording's own times on an absolute schedule: item i is
// released at start + (t_i − t_0) / rate on CLOCK_MONOTONIC. Relative sleeps (sleep_for(t_i −
// t_{i−1})) add each item's processing time and wake-up latency to the schedule and drift (22 %
// slow over 3 s in our measurement); an absolute schedule catches up after a late wake-up
// instead. Every replay (pcap, video, serial) and playback uses this one.
#pragma once

#include <cstdint>

#include "sim/apps/stop_signal.hpp"

namespace sim::apps {

class Pacer {
 public:
  // rate: recording seconds per wall-clock second (1 = as recorded); 0 or less: no waiting.
  explicit Pacer(double rate) noexcept : rate_(rate) {}

  // Sleeps until the release time of an item recorded at `recorded_ns`; the first call anchors
  // the schedule. Returns false, early, once a stop is requested.
  bool wait(std::int64_t recorded_ns, const StopSignal& stop) noexcept;

  // Moves later recording times by `shift_ns` on the schedule: a loop of the recording
  // continues after its last item instead of jumping back to its start.
  void shift(std::int64_t shift_ns) noexcept { offset_ns_ += shift_ns; }

  // How late the most recent release was, ns (0 when on time or unpaced).
  std::int64_t last_lateness_ns() const noexcept { return lateness_ns_; }
  // Times the schedule was started again because the replay fell more than a second behind
  // (a stopped process, a slow disk): it then goes on at the recorded pace rather than publish
  // a burst of stale items.
  std::uint64_t restarts() const noexcept { return restarts_; }

 private:
  double rate_;
  bool anchored_ = false;
  std::int64_t start_ns_ = 0;           // CLOCK_MONOTONIC of the anchor
  std::int64_t anchor_recorded_ns_ = 0;  // its recording time
  std::int64_t offset_ns_ = 0;
  std::int64_t lateness_ns_ = 0;
  std::uint64_t restarts_ = 0;
};

}  // namespace sim::apps
