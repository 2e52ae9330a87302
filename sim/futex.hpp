// SPDX-License-Identifier: Apache-2.0
// Cross-process futex on a word in the region (not FUTEX_PRIVATE: other processes share it).
#pragma once

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstdint>
#include <ctime>

namespace sim::detail {

// Sleeps while *word == expected, until woken or CLOCK_MONOTONIC reaches deadline_ns.
inline void futex_wait_until(const std::atomic<std::uint32_t>* word, std::uint32_t expected,
                             std::int64_t deadline_ns) noexcept {
  timespec deadline{};
  deadline.tv_sec = deadline_ns / 1'000'000'000;
  deadline.tv_nsec = deadline_ns % 1'000'000'000;
  // FUTEX_WAIT_BITSET takes an absolute CLOCK_MONOTONIC deadline, so retries do not drift.
  syscall(SYS_futex, const_cast<std::atomic<std::uint32_t>*>(word), FUTEX_WAIT_BITSET, expected,
          &deadline, nullptr, FUTEX_BITSET_MATCH_ANY);
}

// Wakes every sleeper on `word`; returns how many there were.
inline long futex_wake_all(std::atomic<std::uint32_t>* word) noexcept {
  return syscall(SYS_futex, word, FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

}  // namespace sim::detail
