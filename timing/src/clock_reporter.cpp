// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/clock_reporter.hpp"

#include <cstdio>
#include <utility>

#include "sim/clock.hpp"

namespace sim::timing {

void ClockReporter::set_tolerance(const ClockTolerance& tolerance) noexcept {
  check_ = ClockCheck(tolerance);
  first_tick_ns_ = 0;
  last_judged_ns_ = 0;
  last_.reset();
  judged_.reset();
}

void ClockReporter::set_sources(ClockSources sources) {
  if (sources.stamp_fallback == StampFallback::off) {
    stamps_ = StampSwitch();
  } else if (!stamps_.enabled()) {
    stamps_ = StampSwitch(sources.stamp_fallback);
  }
  sources_ = std::move(sources);
}

std::int64_t ClockReporter::switch_stamp(Writer& writer, std::int64_t sensor_stamp_ns, std::int64_t host_ns) {
  const auto choice = stamps_.choose(sensor_stamp_ns, host_ns,
                                     judged_ ? std::optional(judged_->verdict) : std::nullopt);
  if (choice.event == StampEvent::none) return choice.stamp_ns;
  const std::string line = stamps_.explain(choice, judged_ ? &*judged_ : nullptr);
  if (sources_.log) {
    sources_.log(line);
  } else {
    std::fprintf(stderr, "%s\n", line.c_str());
  }
  if (judged_ && choice.event != StampEvent::held) {
    ClockStatus clock = *judged_;
    stamps_.describe(clock);
    last_ = clock;
    write_clock(writer, clock);
  }
  return choice.stamp_ns;
}

void ClockReporter::add(const std::optional<std::int64_t>& sensor_ns, std::int64_t stamp_offset_ns,
                        std::int64_t arrival_ns) noexcept {
  if (sensor_ns) check_.add(saturating_add_ns(*sensor_ns, stamp_offset_ns), arrival_ns);
}

ClockStatus ClockReporter::reported() const {
  ClockStatus reported = sources_.reported ? sources_.reported() : ClockStatus{};
  // A replay's stamps are the recording's, a restamped replay's this host's: no sensor report
  // describes them, whatever the sensor said when it was recorded.
  if (base_ == ClockBase::replayed) {
    reported.source = ClockSource::replayed;
    reported.stamps = StampClock::sensor;
  } else if (base_ == ClockBase::restamped) {
    reported = ClockStatus{};
    reported.source = ClockSource::host;
    reported.stamps = StampClock::host_arrival;
  } else if (reported.stamps == StampClock::unknown) {
    reported.stamps = StampClock::sensor;
  }
  return reported;
}

ClockStatus ClockReporter::unjudged() const {
  ClockStatus clock = reported();
  clock.verdict = ClockVerdict::unknown;
  clock.problem = kNotJudged;  // a sensor's own words wait for the judgement that weighs them
  stamps_.describe(clock);
  return clock;
}

void ClockReporter::write_first(Writer& writer) {
  write_clock(writer, last_ ? *last_ : unjudged());
  record_written_ = true;
}

ClockStatus ClockReporter::judge(std::int64_t now_realtime_ns) {
  const ClockStatus host = sources_.host ? sources_.host() : ClockStatus{};
  ClockStatus clock = check_.judge(reported(), host, now_realtime_ns);
  judged_ = clock;
  stamps_.describe(clock);
  last_judged_ns_ = now_realtime_ns;
  last_ = clock;
  return clock;
}

std::optional<ClockStatus> ClockReporter::tick(Writer& writer, std::int64_t now_realtime_ns,
                                               bool at_once) {
  start(writer);
  if (check_.packets() == 0) return std::nullopt;
  if (first_tick_ns_ == 0) first_tick_ns_ = now_realtime_ns;
  const bool due = at_once || (last_ ? saturating_sub_ns(now_realtime_ns, last_judged_ns_) >= kPeriodNs ||
                                           now_realtime_ns < last_judged_ns_  // the host's clock was set back
                                     : saturating_sub_ns(now_realtime_ns, first_tick_ns_) >= kFirstNs);
  if (!due) return std::nullopt;
  ClockStatus clock = judge(now_realtime_ns);
  write_clock(writer, clock);
  record_written_ = true;
  return clock;
}

bool write_clock(Writer& writer, const ClockStatus& clock) {
  // Refused only for a record that cannot be stored (ClockCheck keeps its sentences short and
  // its numbers finite); the stream then keeps the last one written.
  return writer.set_clock(clock).has_value();
}

}  // namespace sim::timing
