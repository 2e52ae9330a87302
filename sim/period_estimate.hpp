// SPDX-License-Identifier: Apache-2.0
// The writer's publish period as readers and sim_ls see it (internal; kept in Liveness).
#pragma once

#include <cstdint>

namespace sim::detail {

// The writer's publish period, robust to jitter and to missed frames: a gap of about k periods
// counts as k intervals of gap/k, unless gaps keep coming (then the sensor really slowed down).
class PeriodEstimate {
 public:
  void add(std::int64_t interval_ns) noexcept {
    if (interval_ns <= 0) return;
    if (period_ns_ == 0) {
      period_ns_ = interval_ns;
      return;
    }
    std::int64_t sample = interval_ns;
    if (interval_ns > period_ns_ + period_ns_ / 2 && ++gaps_in_a_row_ < kGapsBeforeRateChange) {
      sample = interval_ns / ((interval_ns + period_ns_ / 2) / period_ns_);
    } else if (interval_ns <= period_ns_ + period_ns_ / 2) {
      gaps_in_a_row_ = 0;
    } else {
      period_ns_ = interval_ns;  // the rate changed: start again from the new interval
      jitter_ns_ = 0;
      gaps_in_a_row_ = 0;
      return;
    }
    const std::int64_t deviation = sample > period_ns_ ? sample - period_ns_ : period_ns_ - sample;
    period_ns_ += (sample - period_ns_) / kSmoothing;
    jitter_ns_ += (deviation - jitter_ns_) / kSmoothing;
  }
  std::int64_t period_ns() const noexcept { return period_ns_; }
  std::int64_t jitter_ns() const noexcept { return jitter_ns_; }

 private:
  static constexpr std::int64_t kSmoothing = 8;  // each frame moves the estimate by 1/8
  static constexpr int kGapsBeforeRateChange = 4;
  std::int64_t period_ns_ = 0;
  std::int64_t jitter_ns_ = 0;
  int gaps_in_a_row_ = 0;
};

}  // namespace sim::detail
