// SPDX-License-Identifier: Apache-2.0
// The clock a sensor last reported (sim::ClockStatus), shared with a reader on another thread:
// the driver sets it as reports come (a position packet, a camera's PTP features), and the clock
// check that judges and writes the stream's record once a second takes it as its
// std::function<ClockStatus()>. Copies share one state, so a copy stays valid when the driver's
// object moves or goes away. Sensors polled over the network use a ClockPoller instead.
#pragma once

#include <memory>
#include <mutex>

#include "sim/clock_status.hpp"

namespace sim::timing {

class ReportedClock {
 public:
  ReportedClock() : state_(std::make_shared<State>()) {}
  explicit ReportedClock(const ClockStatus& initial) : ReportedClock() { state_->clock = initial; }
  // Copies only (a move copies too), so no handle is ever left without its state.
  ReportedClock(const ReportedClock&) = default;
  ReportedClock& operator=(const ReportedClock&) = default;

  ClockStatus operator()() const {
    const std::lock_guard lock(state_->mutex);
    return state_->clock;
  }
  void set(const ClockStatus& clock) {
    const std::lock_guard lock(state_->mutex);
    state_->clock = clock;
  }

 private:
  struct State {
    mutable std::mutex mutex;
    ClockStatus clock;
  };
  std::shared_ptr<State> state_;
};

}  // namespace sim::timing
