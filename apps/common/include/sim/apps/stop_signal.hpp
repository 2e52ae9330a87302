// SPDX-License-Identifier: Apache-2.0
// SIGINT and SIGTERM as a stop request every wait of a program can see promptly: an atomic flag
// for loops, a file descriptor that becomes readable (for poll, epoll, Asio) and sleeps that end
// at once. The handlers are installed without SA_RESTART, so a blocking system call (open of a
// FIFO, a read) returns EINTR instead of hanging. A second signal ends the program the default
// way, for a program stuck where it cannot look.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace sim::apps {

class StopSignal {
 public:
  // Installs the handlers once per process (later calls return the same object). Install before
  // creating streams: a user may stop the program while it is still starting.
  static StopSignal& install();

  bool requested() const noexcept { return flag_.load(std::memory_order_relaxed); }
  // For APIs that take a stop flag (capture loops).
  const std::atomic<bool>& flag() const noexcept { return flag_; }
  // Readable once a stop was requested (an eventfd); never read it.
  int fd() const noexcept { return fd_; }

  // The program ends itself the way a signal would (for example after --duration).
  void request() noexcept;

  // Sleeps until `deadline_ns` on CLOCK_MONOTONIC; false, at once, when a stop is requested.
  bool sleep_until(std::int64_t deadline_ns) const noexcept;
  bool sleep_for(std::chrono::nanoseconds duration) const noexcept;
  bool sleep_for_seconds(double seconds) const noexcept;

  // Tests: forget a request so the next test starts clean.
  void reset_for_test() noexcept;

 private:
  StopSignal();
  std::atomic<bool> flag_{false};
  int fd_ = -1;
};

}  // namespace sim::apps
