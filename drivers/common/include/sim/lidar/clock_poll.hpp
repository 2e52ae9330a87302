// SPDX-License-Identifier: Apache-2.0
// Asking a sensor about its clock, off the frame path: a family's reader (the Hesai PTC one,
// the Ouster HTTP one) called about once a second on a thread of its own, the latest answer
// kept for whoever reports it, and the notes a person needs when the answers look wrong.
//
//   sim::lidar::ClockPoll poll(sim::hesai::PtcClockReader(sensor, model), 1s);
//   ClockStatus now = poll.latest();            // any thread; reported_ns 0 before the first read
//   for (auto& note : poll.take_notes()) status.note(note);   // from the status tick
//
// The reader's every call ends by its own deadline, so stopping (the destructor) waits at most
// one read. A failed read is a ClockStatus with source and state unknown and `problem` saying
// why; the stream never waits for the sensor's clock.
//
// (sim::timing::ClockPoller, in timing/, is the generic poller; this one is the drivers' minimal
// one until that lands. ClockNotes is what the drivers add to either.)
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "sim/clock_status.hpp"

namespace sim::lidar {

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
  bool offset_said_ = false;
  bool changes_said_ = false;
};

// Calls `read` every `period` on its own thread; the latest answer and the notes in between.
class ClockPoll {
 public:
  ClockPoll(std::function<ClockStatus()> read, std::chrono::milliseconds period);
  ClockPoll(const ClockPoll&) = delete;
  ClockPoll& operator=(const ClockPoll&) = delete;
  ~ClockPoll();  // stops: waits for a read under way (bounded by the reader's deadline)

  ClockStatus latest() const;
  std::uint64_t reads() const;  // completed reads
  std::vector<std::string> take_notes();

 private:
  void loop();

  std::function<ClockStatus()> read_;
  std::chrono::milliseconds period_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  ClockStatus latest_{};
  std::uint64_t reads_ = 0;
  ClockNotes notes_;
  std::vector<std::string> pending_;
  std::thread thread_;  // last: starts after everything it uses
};

}  // namespace sim::lidar
