// SPDX-License-Identifier: Apache-2.0
// Maps a device's CLOCK_MONOTONIC timestamps to CLOCK_REALTIME. The offset is re-read for every
// frame (three vDSO clock reads, no system call), so an NTP step or slew shows up in the next
// frame's stamp; drivers that compute it once at start-up drift by hundreds of milliseconds.
#pragma once

#include <cstdint>

#include "sim/clock.hpp"

namespace sim::camera {

class MonotonicToRealtime {
 public:
  MonotonicToRealtime() noexcept { resample(); }

  // Brackets the realtime read between two monotonic reads and takes their midpoint, so the
  // offset's error is at most half the bracket (tens of nanoseconds).
  void resample() noexcept {
    const std::int64_t before = monotonic_ns();
    const std::int64_t real = realtime_ns();
    const std::int64_t after = monotonic_ns();
    offset_ns_ = real - (before + (after - before) / 2);
  }
  std::int64_t offset_ns() const noexcept { return offset_ns_; }
  std::int64_t to_realtime(std::int64_t monotonic) const noexcept { return monotonic + offset_ns_; }

 private:
  std::int64_t offset_ns_ = 0;
};

}  // namespace sim::camera
