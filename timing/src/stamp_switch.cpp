// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/stamp_switch.hpp"

#include "sim/clock.hpp"

namespace sim::timing {
namespace {

constexpr char kMeanwhile[] = " Meanwhile frames are stamped with host arrival time (--stamp-fallback host).";

// `text` cut to at most `size` bytes at a space, marked "...".
void cut_to(std::string& text, std::size_t size) {
  if (text.size() <= size) return;
  const std::size_t space = text.rfind(' ', size - 3);
  text.resize(space == std::string::npos ? 0 : space);
  text += "...";
}

}  // namespace

StampSwitch::Choice StampSwitch::choose(std::int64_t sensor_stamp_ns, std::int64_t host_ns,
                                        std::optional<ClockVerdict> verdict) noexcept {
  if (!enabled()) return {sensor_stamp_ns, StampEvent::none};
  // Untrusted: in error, or not judged yet (a sensor 37 s ahead would otherwise stamp its first
  // frames 37 s ahead, and the switch to host time would then go back 37 s).
  const bool want_host = !verdict || *verdict == ClockVerdict::error;
  Choice choice;
  if (want_host != on_host_) {
    const std::int64_t wanted = want_host ? host_ns : sensor_stamp_ns;
    const bool backwards = last_stamp_ns_ && wanted <= *last_stamp_ns_;
    if (backwards && !held_) {
      held_ = true;  // wait: the new clock may pass the last stamp within a frame or two
      held_since_ns_ = host_ns;
      went_back_ns_ = *last_stamp_ns_ - wanted;
      choice.event = StampEvent::held;
    } else if (!backwards || host_ns - held_since_ns_ >= kLongestHoldNs) {
      went_back_ns_ = backwards ? *last_stamp_ns_ - wanted : 0;
      on_host_ = want_host;
      held_ = false;
      announced_ = want_host && verdict.has_value();
      choice.event = want_host ? StampEvent::to_host : StampEvent::to_sensor;
    }
  } else {
    held_ = false;  // the switch is no longer wanted
    if (on_host_ && verdict && !announced_) {
      announced_ = true;  // on host time from the start: say why once the verdict is in
      choice.event = StampEvent::to_host;
    }
  }
  choice.stamp_ns = on_host_ ? host_ns : sensor_stamp_ns;
  last_stamp_ns_ = choice.stamp_ns;
  return choice;
}

void StampSwitch::describe(ClockStatus& clock) const {
  if (!on_host()) return;
  clock.stamps = StampClock::host_arrival;
  if (clock.problem.empty()) return;  // judged fine: the next frame goes back to the sensor's
  cut_to(clock.problem, ClockStatus::kMaxProblem - (sizeof kMeanwhile - 1));
  clock.problem += kMeanwhile;
}

std::string StampSwitch::explain(const Choice& choice, const ClockStatus* clock) const {
  const std::string verdict = clock != nullptr ? to_string(clock->verdict) : "not judged yet";
  switch (choice.event) {
    case StampEvent::to_host:
      return "stamps: host arrival time from now on: the sensor's clock is " +
             (clock != nullptr ? "in " + verdict + (clock->problem.empty() ? "" : " (" + clock->problem + ")")
                               : verdict) +
             " (--stamp-fallback host)" + went_back();
    case StampEvent::to_sensor:
      return "stamps: the sensor's clock from now on: its verdict is " + verdict + ", no longer error" + went_back();
    case StampEvent::held:
      return "warning: stamps: switching to " + std::string(on_host_ ? "the sensor's clock" : "host arrival time") +
             " now would take the stamps back by " + human_duration(went_back_ns_) + "; the frames keep " +
             (on_host_ ? "host arrival time" : "the sensor's stamps") +
             " for up to 1 s until the new clock passes the last stamp published, then switch anyway "
             "(no frame is reordered)";
    case StampEvent::none:
      break;
  }
  return {};
}

std::string StampSwitch::went_back() const {
  if (went_back_ns_ <= 0) return {};
  return "; warning: the stamps went back by " + human_duration(went_back_ns_) + " at this switch";
}

}  // namespace sim::timing
