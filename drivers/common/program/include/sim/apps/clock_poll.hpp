// SPDX-License-Identifier: Apache-2.0
// Asking a sensor about its clock, off the frame path: a family's reader (sim::hesai::
// PtcClockReader, sim::ouster::HttpClockReader) called about once a second by
// sim::timing::ClockPoller on its own thread, the latest answer kept for whoever reports it, and
// sim::timing::ClockNotes' sentences for the status line.
//
//   sim::apps::ClockPoll poll(sim::hesai::PtcClockReader(sensor, model), 1s);
//   ClockStatus now = poll.latest();   // any thread, never waits; reported_ns 0 before a read
//   for (auto& note : poll.take_notes()) status.note(note);   // from the receive thread's tick
//
// The reader's every call ends by its own deadline, so stopping (the destructor) waits at most
// one read. A failed read is a ClockStatus with source and state unknown, reported_ns 0 and
// `problem` saying why; the stream never waits for the sensor's clock.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/timing/clock_notes.hpp"
#include "sim/timing/clock_poller.hpp"

namespace sim::apps {

// Calls `read` every `period` on its own thread; the latest answer and the notes in between.
class ClockPoll {
 public:
  ClockPoll(std::function<ClockStatus()> read, std::chrono::milliseconds period);

  ClockStatus latest() const { return poller_.latest(); }  // never waits for a read
  std::uint64_t reads() const { return poller_.readings(); }
  std::vector<std::string> take_notes();
  timing::ClockPoller& poller() noexcept { return poller_; }

 private:
  struct Notes {
    std::mutex mutex;
    timing::ClockNotes notes;  // only the poller's thread updates it
    std::vector<std::string> pending;
  };
  std::shared_ptr<Notes> notes_;
  timing::ClockPoller poller_;  // last: its thread uses notes_
};

}  // namespace sim::apps
