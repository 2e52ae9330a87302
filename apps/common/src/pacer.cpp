// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/pacer.hpp"

#include "sim/clock.hpp"

namespace sim::apps {
namespace {

// Items due within this much of now go out without a sleep: a wake-up costs more than that,
// and bursts (dual-return packets arrive back to back) stay bursts.
constexpr std::int64_t kBatchWindowNs = 50'000;
// Further behind than this, the schedule starts again from the late item.
constexpr std::int64_t kMaxLagNs = 1'000'000'000;

}  // namespace

bool Pacer::wait(std::int64_t recorded_ns, const StopSignal& stop) noexcept {
  if (stop.requested()) return false;
  if (rate_ <= 0) return true;
  recorded_ns += offset_ns_;
  const std::int64_t now = monotonic_ns();
  if (!anchored_) {
    anchored_ = true;
    start_ns_ = now;
    anchor_recorded_ns_ = recorded_ns;
    return true;
  }
  const double elapsed = static_cast<double>(recorded_ns - anchor_recorded_ns_) / rate_;
  const std::int64_t deadline = start_ns_ + static_cast<std::int64_t>(elapsed);
  if (now - deadline > kMaxLagNs) {
    ++restarts_;
    start_ns_ = now;
    anchor_recorded_ns_ = recorded_ns;
    lateness_ns_ = 0;
    return true;
  }
  if (deadline - now <= kBatchWindowNs) {
    lateness_ns_ = now > deadline ? now - deadline : 0;
    return true;
  }
  if (!stop.sleep_until(deadline)) return false;
  const std::int64_t woke = monotonic_ns();
  lateness_ns_ = woke > deadline ? woke - deadline : 0;
  return true;
}

}  // namespace sim::apps
