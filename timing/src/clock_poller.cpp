// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/clock_poller.hpp"

#include <utility>

namespace sim::timing {

ClockPoller::ClockPoller(Read read, std::chrono::milliseconds period, Changed changed)
    : read_(std::move(read)),
      changed_(std::move(changed)),
      period_(period.count() > 0 ? period : kDefaultPeriod),
      thread_([this] { run(); }) {}

ClockPoller::~ClockPoller() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

ClockStatus ClockPoller::latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

std::uint64_t ClockPoller::readings() const {
  std::lock_guard lock(mutex_);
  return readings_;
}

bool ClockPoller::wait_for_readings(std::uint64_t count, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  return taken_.wait_for(lock, timeout, [&] { return readings_ > count; });
}

void ClockPoller::poll_now() {
  {
    std::lock_guard lock(mutex_);
    poll_now_ = true;
  }
  wake_.notify_all();
}

void ClockPoller::run() {
  ClockStatus previous{};
  bool first = true;
  for (;;) {
    // `read` runs without the lock: latest() never waits for a slow sensor.
    ClockStatus current = read_ ? read_() : ClockStatus{};
    const bool changed = first || !same_synchronisation(previous, current);
    if (changed && changed_) changed_(previous, current);
    first = false;
    previous = current;
    std::unique_lock lock(mutex_);
    latest_ = std::move(current);
    ++readings_;
    taken_.notify_all();
    wake_.wait_for(lock, period_, [this] { return stop_ || poll_now_; });
    if (stop_) return;
    poll_now_ = false;
  }
}

bool same_synchronisation(const ClockStatus& a, const ClockStatus& b) noexcept {
  return a.source == b.source && a.state == b.state && a.ptp_domain == b.ptp_domain &&
         a.grandmaster == b.grandmaster && a.verdict == b.verdict && a.problem == b.problem;
}

}  // namespace sim::timing
