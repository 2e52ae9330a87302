// SPDX-License-Identifier: Apache-2.0
#include "pacer.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>

#include "sim/clock.hpp"

namespace sim::pcap {
namespace {

// Packets due within this much of now go out without a sleep: a wake-up costs more than that,
// and bursts (dual-return packets arrive back to back) stay bursts.
constexpr std::int64_t batch_window_ns = 50'000;
// Long waits (a slow --rate) are cut into slices so a stop request is seen promptly.
constexpr std::int64_t max_slice_ns = 100'000'000;

timespec to_timespec(std::int64_t ns) noexcept {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

}  // namespace

bool Pacer::wait(std::int64_t capture_ns, const std::atomic<bool>& stop) noexcept {
  if (stop.load(std::memory_order_relaxed)) return false;
  if (rate_ <= 0) return true;
  capture_ns += offset_ns_;
  if (!anchored_) {
    anchored_ = true;
    start_ns_ = monotonic_ns();
    first_capture_ns_ = capture_ns;
    return true;
  }
  const double elapsed = static_cast<double>(capture_ns - first_capture_ns_) / rate_;
  const std::int64_t deadline = start_ns_ + static_cast<std::int64_t>(elapsed);
  for (;;) {
    const std::int64_t now = monotonic_ns();
    if (deadline - now <= batch_window_ns) {
      lateness_ns_ = std::max<std::int64_t>(0, now - deadline);
      return !stop.load(std::memory_order_relaxed);
    }
    const timespec until = to_timespec(std::min(deadline, now + max_slice_ns));
    const int rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
    if (stop.load(std::memory_order_relaxed)) return false;
    if (rc != 0 && rc != EINTR) return !stop.load(std::memory_order_relaxed);  // cannot sleep: go
  }
}

}  // namespace sim::pcap
