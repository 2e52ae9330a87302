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

}  // namespace sim
