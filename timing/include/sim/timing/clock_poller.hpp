// SPDX-License-Identifier: Apache-2.0
// Reads a clock about once a second on its own thread, off every frame path: the host's own
// synchronisation (HostClockWatch), or a sensor's (Hesai PTC, Ouster HTTP, Velodyne position
// packets). A sensor that does not answer never delays the stream: only the poller's thread
// waits for `read`, the caller gets the last reading at once.
//
//   sim::timing::ClockPoller poller([&] { return read_sensor_clock(device); });
//   ...
//   writer.set_clock(check.judge(poller.latest(), host.latest(), sim::realtime_ns()));
//
// `read` must return within its own bound (a socket timeout): the destructor waits for a read in
// progress before it returns, and nothing else.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

#include "sim/clock_status.hpp"

namespace sim::timing {

class ClockPoller {
 public:
  using Read = std::function<ClockStatus()>;
  // Called on the poller's thread after a reading that differs from the previous one in what it
  // says of the synchronisation (same_synchronisation), and after the first reading, with the
  // previous reading (a default ClockStatus before the first). Keep it short: a log line.
  using Changed = std::function<void(const ClockStatus& previous, const ClockStatus& current)>;

  static constexpr std::chrono::milliseconds kDefaultPeriod{1000};

  // Starts the thread; the first reading happens at once, then one every `period` (measured from
  // the end of a reading, so a slow `read` never piles up).
  explicit ClockPoller(Read read, std::chrono::milliseconds period = kDefaultPeriod,
                       Changed changed = {});
  ClockPoller(const ClockPoller&) = delete;
  ClockPoller& operator=(const ClockPoller&) = delete;
  // Wakes the thread and joins it: returns at once between readings, or once a reading in
  // progress returns.
  ~ClockPoller();

  // The last reading; a default ClockStatus (source and state unknown, reported_ns 0) before the
  // first. Never waits for a reading: a mutex held only to copy the record.
  ClockStatus latest() const;
  // How many readings were taken so far.
  std::uint64_t readings() const;
  // Waits until more than `count` readings were taken, at most `timeout`; whether they were.
  bool wait_for_readings(std::uint64_t count, std::chrono::milliseconds timeout) const;
  // Asks for a reading now instead of at the end of the period (after a reconfiguration).
  void poll_now();

 private:
  void run();

  Read read_;
  Changed changed_;
  std::chrono::milliseconds period_;
  mutable std::mutex mutex_;
  mutable std::condition_variable wake_;   // the thread: stop or poll now
  mutable std::condition_variable taken_;  // waiters for a reading
  ClockStatus latest_{};
  std::uint64_t readings_ = 0;
  bool stop_ = false;
  bool poll_now_ = false;
  std::thread thread_;  // last: started after every other member exists
};

// Whether two readings say the same of the synchronisation: source, state, domain, grandmaster,
// verdict and problem (offsets, delays and times may differ). A change of any of these is what a
// log line is for.
bool same_synchronisation(const ClockStatus& a, const ClockStatus& b) noexcept;

}  // namespace sim::timing
