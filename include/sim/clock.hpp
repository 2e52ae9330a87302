// SPDX-License-Identifier: Apache-2.0
// The two clocks every frame carries: sensor time on CLOCK_REALTIME (comparable across hosts),
// publish time on CLOCK_MONOTONIC (immune to clock steps, for latency and liveness).
#pragma once

#include <cstdint>
#include <ctime>

namespace sim {

inline std::int64_t clock_ns(clockid_t clock) noexcept {
  timespec ts{};
  clock_gettime(clock, &ts);  // vDSO: no system call
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}
inline std::int64_t realtime_ns() noexcept { return clock_ns(CLOCK_REALTIME); }
inline std::int64_t monotonic_ns() noexcept { return clock_ns(CLOCK_MONOTONIC); }

// a + b and a − b for stamps in nanoseconds, held at the int64 limits instead of overflowing: a
// sensor's clock is outside data, and a corrupt one must give a wrong stamp, never undefined
// behaviour.
constexpr std::int64_t saturating_add_ns(std::int64_t a, std::int64_t b) noexcept {
  std::int64_t sum = 0;
  if (!__builtin_add_overflow(a, b, &sum)) return sum;
  return b > 0 ? INT64_MAX : INT64_MIN;
}
constexpr std::int64_t saturating_sub_ns(std::int64_t a, std::int64_t b) noexcept {
  std::int64_t difference = 0;
  if (!__builtin_sub_overflow(a, b, &difference)) return difference;
  return b < 0 ? INT64_MAX : INT64_MIN;
}

}  // namespace sim
