// SPDX-License-Identifier: Apache-2.0
// What the families' clock readers (the Hesai PTC one, the Ouster HTTP one) share: the report of
// a read that failed, and the notes a person needs when successive reports look wrong. The
// polling itself is sim::timing::ClockPoller's, in the programs (sim/apps/clock_poll.hpp).
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "sim/clock_status.hpp"

namespace sim::timing {

// The report of a read that failed: source and state unknown, reported_ns 0, `why` (one
// sentence, cut to ClockStatus::kMaxProblem bytes at a character boundary) as the problem.
ClockStatus clock_read_failed(std::string_view why);

// Watches successive reports of one sensor's clock and says, in one sentence each, what a person
// must know: the clock's state changed, it says "locked" yet lies far from its master, its
// grandmaster keeps changing, it cannot be read (and again can). Each kind is said at most once
// a minute while it lasts.
class ClockNotes {
 public:
  struct Limits {
    std::int64_t locked_offset_ns = 1'000'000;      // "locked" beyond this is suspicious
    int grandmaster_changes = 3;                     // changes within `window` that are a warning
    std::int64_t window_ns = 60'000'000'000;         // and the repeat interval of each warning
  };
  ClockNotes() = default;
  explicit ClockNotes(Limits limits) : limits_(limits) {}

  // The notes about `status` (read at `now_ns`, CLOCK_MONOTONIC), given the ones before it.
  std::vector<std::string> update(const ClockStatus& status, std::int64_t now_ns);

 private:
  bool due(std::int64_t& last_ns, std::int64_t now_ns) const noexcept;

  Limits limits_{};
  bool first_ = true;
  bool failing_ = false;
  ClockSource source_ = ClockSource::unknown;
  ClockState state_ = ClockState::unknown;
  std::string grandmaster_;
  std::deque<std::int64_t> changes_;  // when the grandmaster changed, within the window
  std::int64_t offset_said_ns_ = 0;
  std::int64_t changes_said_ns_ = 0;
};

}  // namespace sim::timing
