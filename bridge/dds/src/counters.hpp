// SPDX-License-Identifier: Apache-2.0
// What the status line and --json report for each bridged topic. Written by the topic's own
// thread, read by the main thread: relaxed atomics, since each is a tally on its own.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

namespace sim::bridge {

struct Counters {
  std::atomic<std::uint64_t> frames_seen{0};    // SIM frames published on the stream, or DDS
                                                // messages received (subscribe)
  std::atomic<std::uint64_t> bridged{0};        // messages written to DDS / frames into SIM
  std::atomic<std::uint64_t> serialized{0};     // messages serialized into a DDS payload
  std::atomic<std::uint64_t> no_reader{0};      // frames left alone: no remote reader matched
  std::atomic<std::uint64_t> skipped_rate{0};   // frames dropped by --max-rate
  std::atomic<std::uint64_t> torn{0};           // frames overwritten while being copied
  std::atomic<std::uint64_t> malformed{0};      // received messages dropped as malformed
  std::atomic<std::uint64_t> failed{0};         // writes DDS or SIM refused
  std::atomic<std::int32_t> matched{0};         // remote readers (publish) or writers (subscribe)
  std::atomic<bool> connected{false};           // the SIM stream / the DDS topic is open

  void count(std::atomic<std::uint64_t>& c) { c.fetch_add(1, std::memory_order_relaxed); }

  // The last problem worth telling the user, shown once by the main thread; a problem that
  // repeats (a stream that stays unusable, a flood of the same bad message) is told only once.
  void problem(std::string sentence) {
    std::lock_guard lock(mutex_);
    if (sentence != told_) problem_ = std::move(sentence);
  }
  std::string take_problem() {
    std::lock_guard lock(mutex_);
    if (!problem_.empty()) told_ = problem_;
    return std::exchange(problem_, {});
  }

 private:
  std::mutex mutex_;
  std::string problem_;
  std::string told_;
};

}  // namespace sim::bridge
