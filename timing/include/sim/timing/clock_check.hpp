// SPDX-License-Identifier: Apache-2.0
// Checks a stream's clock by its data: each packet's own sensor time against that packet's
// arrival on this host (for a replay: the packet's capture time, the recording host's clock).
// Never a frame's stamp against the frame's completion: a frame takes a revolution to complete.
//
//   sim::timing::ClockCheck check;                  // one per stream
//   check.add(packet_sensor_ns, packet_arrival_ns); // per packet, on the receive path: cheap
//   writer.set_clock(check.judge(reported, host, sim::realtime_ns()));  // about once a second
#pragma once

#include <cstdint>

#include "sim/clock_status.hpp"

namespace sim::timing {

// What counts as fine, per stream (a camera's exposure and transfer time is not an error).
struct ClockTolerance {
  std::int64_t offset_ok_ns = 10'000'000;       // |median offset to host| up to this: ok
  std::int64_t offset_error_ns = 1'000'000'000; // beyond this: error (cannot be paired)
  std::int64_t spread_warn_ns = 5'000'000;      // a spread wider than this: warn
  std::int64_t step_ns = 500'000'000;           // a jump of the offset beyond this is a step
  double drift_warn_ppm = 50.0;                 // |drift| beyond this: warn (a free-running clock)
  std::int64_t future_ns = 1'000'000'000;       // a stamp this far ahead of its arrival: "future"
};

class ClockCheck {
 public:
  explicit ClockCheck(ClockTolerance tolerance = {});

  // One packet: its sensor time and its arrival (host CLOCK_REALTIME, or a replay's capture
  // time). Called on the receive path: constant time, no allocation, no system call.
  void add(std::int64_t sensor_ns, std::int64_t arrival_ns) noexcept;

  // A replay's --loop started over: the next packet begins a new measurement, neither a step
  // nor time going backwards.
  void restart() noexcept;

  // Off the frame path (about once a second): `reported` (what the sensor says: source, state,
  // grandmaster…; its measured and verdict fields are ignored) with the measured fields filled in
  // and the verdict and problem sentence set, judged also against `host` (the host's own clock,
  // from HostClockWatch; a default ClockStatus when unknown).
  ClockStatus judge(const ClockStatus& reported, const ClockStatus& host,
                    std::int64_t now_realtime_ns);

  const ClockTolerance& tolerance() const noexcept { return tolerance_; }

 private:
  ClockTolerance tolerance_;
  // The helper who writes clock_check.cpp adds the state here.
};

}  // namespace sim::timing
