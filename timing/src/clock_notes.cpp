// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/clock_notes.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "sim/clock.hpp"

namespace sim::timing {
namespace {

// The magnitude of a signed offset, without overflow at INT64_MIN.
std::uint64_t magnitude(std::int64_t ns) noexcept {
  return ns < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(ns) : static_cast<std::uint64_t>(ns);
}

// "12 µs", "10.0 s", "3.2 h": enough to see the size (the core's human_duration is the
// report's; this is the note's and does not depend on it).
std::string size_text(std::uint64_t ns) {
  char text[48];
  if (ns < 1'000'000) {
    std::snprintf(text, sizeof text, "%llu µs", static_cast<unsigned long long>(ns / 1000));
  } else if (ns < 1'000'000'000) {
    std::snprintf(text, sizeof text, "%.1f ms", static_cast<double>(ns) / 1e6);
  } else if (ns < 3'600'000'000'000ULL) {
    std::snprintf(text, sizeof text, "%.1f s", static_cast<double>(ns) / 1e9);
  } else {
    std::snprintf(text, sizeof text, "%.1f h", static_cast<double>(ns) / 3.6e12);
  }
  return text;
}

const char* source_word(ClockSource s) noexcept {
  switch (s) {
    case ClockSource::host: return "host";
    case ClockSource::ptp: return "PTP";
    case ClockSource::gptp: return "gPTP";
    case ClockSource::pps_nmea: return "PPS/NMEA";
    case ClockSource::sync_pulse: return "sync pulse";
    case ClockSource::free_running: return "free-running";
    case ClockSource::replayed: return "replayed";
    case ClockSource::unknown: break;
  }
  return "unknown";
}

const char* state_word(ClockState s) noexcept {
  switch (s) {
    case ClockState::locked: return "locked";
    case ClockState::acquiring: return "acquiring";
    case ClockState::holdover: return "in holdover";
    case ClockState::free_running: return "free running";
    case ClockState::unknown: break;
  }
  return "in an unknown state";
}

}  // namespace

ClockStatus clock_read_failed(std::string_view why) {
  std::size_t size = std::min(why.size(), ClockStatus::kMaxProblem);
  // Not inside a UTF-8 sequence: back off continuation bytes.
  while (size > 0 && size < why.size() && (static_cast<unsigned char>(why[size]) & 0xC0) == 0x80) --size;
  ClockStatus clock;
  clock.problem = std::string(why.substr(0, size));
  return clock;
}

bool ClockNotes::due(std::int64_t& last_ns, std::int64_t now_ns) const noexcept {
  if (last_ns != 0 && now_ns - last_ns < limits_.window_ns) return false;
  last_ns = now_ns;
  return true;
}

std::vector<std::string> ClockNotes::update(const ClockStatus& status, std::int64_t now_ns) {
  std::vector<std::string> notes;
  const bool failed = status.reported_ns == 0 && !status.problem.empty();
  if (failed) {
    if (!failing_) notes.push_back("warning: cannot read the sensor's clock: " + status.problem);
    failing_ = true;
    return notes;
  }
  if (failing_) notes.emplace_back("the sensor's clock can be read again");
  failing_ = false;
  if (first_ || status.source != source_ || status.state != state_) {
    notes.push_back(std::string("the sensor's clock: ") + source_word(status.source) + ", " +
                    state_word(status.state) +
                    (status.grandmaster.empty() ? "" : ", grandmaster " + status.grandmaster));
  }
  first_ = false;
  source_ = status.source;
  state_ = status.state;

  const bool far = status.state == ClockState::locked && status.offset_from_master_ns &&
                   magnitude(*status.offset_from_master_ns) > static_cast<std::uint64_t>(limits_.locked_offset_ns);
  if (!far) offset_said_ns_ = 0;
  if (far && due(offset_said_ns_, now_ns)) {
    notes.push_back("warning: the sensor says its clock is locked, yet " +
                    size_text(magnitude(*status.offset_from_master_ns)) +
                    " from its master; do not trust its stamps until the offset settles (check "
                    "the grandmaster and the sensor's PTP settings)");
  }

  if (!status.grandmaster.empty() && status.grandmaster != grandmaster_) {
    if (!grandmaster_.empty()) changes_.push_back(now_ns);
    grandmaster_ = status.grandmaster;
  }
  while (!changes_.empty() && now_ns - changes_.front() > limits_.window_ns) changes_.pop_front();
  const bool flapping = static_cast<int>(changes_.size()) >= limits_.grandmaster_changes;
  if (!flapping) changes_said_ns_ = 0;
  if (flapping && due(changes_said_ns_, now_ns)) {
    notes.push_back("warning: the sensor's grandmaster changed " + std::to_string(changes_.size()) +
                    " times within a minute (now " + grandmaster_ +
                    "); two masters may be competing: check that one grandmaster serves the "
                    "sensor's PTP domain");
  }
  return notes;
}

}  // namespace sim::timing
