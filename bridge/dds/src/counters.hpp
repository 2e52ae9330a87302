// SPDX-License-Identifier: Apache-2.0
// What the status line and --json report for each bridged topic. Written by the topic's own
// thread, read by the main thread: relaxed atomics, since each is a tally on its own.
#pragma once

#include <atomic>
#include <cstdint>
#include <algorithm>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

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

  // A problem worth telling the user, shown by the main thread at its next report. Distinct
  // sentences are all told (up to max_pending per report; review L3: only the last one of a period
  // used to be); one that was told already (a stream that stays unusable, a flood of the same bad
  // message) is not told again.
  void problem(std::string sentence) {
    std::lock_guard lock(mutex_);
    if (told_.count(sentence) != 0 || pending_.size() >= max_pending) return;
    if (std::find(pending_.begin(), pending_.end(), sentence) == pending_.end()) {
      pending_.push_back(std::move(sentence));
    }
  }
  std::vector<std::string> take_problems() {
    std::lock_guard lock(mutex_);
    if (told_.size() > max_told) told_.clear();  // bounded memory under endless distinct input
    for (const std::string& p : pending_) told_.insert(p);
    return std::exchange(pending_, {});
  }

 private:
  static constexpr std::size_t max_pending = 8;
  static constexpr std::size_t max_told = 256;
  std::mutex mutex_;
  std::vector<std::string> pending_;
  std::set<std::string> told_;
};

}  // namespace sim::bridge
