// SPDX-License-Identifier: Apache-2.0
// StampSwitch: the rule of --stamp-fallback host, the opt-in fix for a sensor clock in error.
// While the stream's clock verdict is `error` (or not judged yet), frames are stamped with their
// host arrival time instead of the sensor's; once it is not, with the sensor's again. Decided
// at frame boundaries (a frame keeps one clock). A switch that would take the stamps backwards
// waits, with one warning, until the new clock's stamp passes the last one published, for up to
// a second (a clock a frame or two behind); a clock further off than that would never pass it,
// so the switch then happens anyway and its log line says by how much the stamps went back. A
// new switch starts on host time (untrusted until judged), so a sensor 37 s ahead never has its
// stamps published and then stepped back from.
//
//   StampSwitch stamps(StampFallback::host);
//   const auto choice = stamps.choose(sensor_stamp_ns, host_receive_ns, last_verdict);
//   if (choice.event != StampEvent::none) log(stamps.describe(choice, problem));
//   commit(choice.stamp_ns);
//
// No allocation in choose(); only a switch (rare) builds sentences.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sim/clock_status.hpp"

namespace sim::timing {

// --stamp-fallback: what a live stream stamps its frames with while its sensor clock is untrusted.
enum class StampFallback {
  off,   // the sensor's stamps whatever the verdict (the default)
  host,  // the host's arrival time while the verdict is error or not judged yet
};

// What a frame's choice changed.
enum class StampEvent {
  none,
  to_host,        // from this frame on (or, at the first verdict, still): host arrival time
  to_sensor,      // from this frame on: the sensor's stamps again
  held,           // a switch would take the stamps backwards: it waits up to kLongestHoldNs
};

class StampSwitch {
 public:
  struct Choice {
    std::int64_t stamp_ns = 0;
    StampEvent event = StampEvent::none;
  };

  static constexpr std::int64_t kLongestHoldNs = 1'000'000'000;  // host time a switch may wait

  explicit StampSwitch(StampFallback fallback = StampFallback::off) noexcept : fallback_(fallback) {}

  bool enabled() const noexcept { return fallback_ == StampFallback::host; }
  // Frames are stamped with host arrival time now (a new switch starts there: the sensor's clock
  // is untrusted until judged).
  bool on_host() const noexcept { return enabled() && on_host_; }

  // A frame's stamp: `sensor_stamp_ns` (the sensor's, any stamp offset applied) or its arrival
  // `host_ns`, by the last verdict (nullopt: not judged yet).
  Choice choose(std::int64_t sensor_stamp_ns, std::int64_t host_ns,
                std::optional<ClockVerdict> verdict) noexcept;

  // `clock` (a judgement of the sensor's clock) as the record says it while frames are stamped
  // as now: `stamps` host_arrival on host time, and the problem sentence saying so; else as is.
  void describe(ClockStatus& clock) const;
  // The log line of a choice's event (not `none`): what changed and why (`clock`: the last
  // judgement, nullptr before one).
  std::string explain(const Choice& choice, const ClockStatus* clock) const;

 private:
  std::string went_back() const;

  StampFallback fallback_;
  bool on_host_ = true;         // untrusted until judged
  bool held_ = false;           // the wanted switch waits; warned
  bool announced_ = false;      // a judgement said why the frames are on host time
  std::int64_t held_since_ns_ = 0;  // host time the wait began
  std::int64_t went_back_ns_ = 0;   // how far back the switch would take (or took) the stamps
  std::optional<std::int64_t> last_stamp_ns_;
};

}  // namespace sim::timing
