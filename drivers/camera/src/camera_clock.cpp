// SPDX-License-Identifier: Apache-2.0
#include "sim/camera/camera_clock.hpp"

#include <array>
#include <cctype>
#include <cstdio>
#include <string_view>

namespace sim::camera {
namespace {

bool same_word(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

// The PTP port states of the SFNC enumeration; GevIEEE1588Status numbers them 1–9 in this order
// (as linuxptp's PS_* do), which a camera may show instead of the names.
constexpr std::array<std::string_view, 9> port_states{
    "Initializing", "Faulty", "Disabled", "Listening", "PreMaster", "Master", "Passive", "Uncalibrated", "Slave"};

// "Slave", "slave", "9", "PRE_MASTER" → "Slave", … ; "" when it is none of them.
std::string_view port_state(std::string_view status) noexcept {
  if (status.size() == 1 && status[0] >= '1' && status[0] <= '9') {
    return port_states[static_cast<std::size_t>(status[0] - '1')];
  }
  std::string squeezed;
  for (char c : status) {
    if (c != '_' && c != ' ' && c != '-') squeezed += c;
  }
  for (std::string_view state : port_states) {
    if (same_word(squeezed, state)) return state;
  }
  return {};
}

void set_problem(ClockStatus& clock, const std::string& problem) {
  clock.verdict = ClockVerdict::warn;
  clock.problem = problem.substr(0, ClockStatus::kMaxProblem);
}

// What a port state that is not Slave means for the clock; `state` is one of port_states.
std::string not_following(std::string_view state, ClockState& clock_state) {
  if (state == "Master") {
    clock_state = ClockState::free_running;
    return "the camera is the PTP master of its network: no better clock answers, so its stamps are its own "
           "oscillator's; run a grandmaster (ptp4l) on the host or the switch";
  }
  if (state == "Faulty") {
    clock_state = ClockState::holdover;
    return "the camera reports its PTP port faulty: its clock drifts from the last synchronisation; check the "
           "network and the master";
  }
  if (state == "Disabled") {
    clock_state = ClockState::free_running;
    return "PTP is enabled on the camera but its port is disabled: its clock free-runs; check the camera's "
           "PTP settings";
  }
  clock_state = ClockState::acquiring;  // Initializing, Listening, PreMaster, Uncalibrated, Passive
  return "the camera's PTP port is " + std::string(state) +
         ", not following a master yet: its stamps are not to be trusted until it is Slave";
}

// PTP on: the port state (and the servo's) as a clock state, with the sentence of a problem.
void ptp_state(const PtpReading& ptp, ClockStatus& clock) {
  const std::string_view state = port_state(ptp.status);
  if (state == "Slave") {
    const bool servo_locked = ptp.servo.empty() || same_word(ptp.servo, "Locked");
    clock.state = servo_locked ? ClockState::locked : ClockState::acquiring;
    if (!servo_locked) {
      set_problem(clock, "the camera follows a PTP master but its servo is not locked yet (" + ptp.servo +
                             "); its stamps settle within a minute");
    }
    return;
  }
  if (state.empty()) {
    clock.state = ClockState::unknown;
    set_problem(clock, ptp.status.empty()
                           ? "PTP is enabled on the camera but it reports no PTP status, so nothing says it is locked"
                           : "the camera reports PTP status '" + ptp.status +
                                 "', which is no PTP port state, so nothing says it is locked");
    return;
  }
  set_problem(clock, not_following(state, clock.state));
}

}  // namespace

timing::ClockTolerance camera_clock_tolerance() noexcept {
  timing::ClockTolerance tolerance;
  tolerance.offset_ok_ns = 250'000'000;
  tolerance.spread_warn_ns = 50'000'000;
  return tolerance;
}

std::string clock_identity_text(std::uint64_t identity) {
  std::array<unsigned, 8> b{};
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<unsigned>((identity >> (8 * (7 - i))) & 0xff);
  char text[24];
  std::snprintf(text, sizeof text, "%02x%02x%02x.%02x%02x.%02x%02x%02x", b[0], b[1], b[2], b[3], b[4], b[5],
                b[6], b[7]);
  return text;
}

ClockStatus genicam_clock_status(const PtpReading& ptp, bool device_time, std::int64_t reported_ns) {
  ClockStatus clock;
  clock.reported_ns = reported_ns;
  clock.stamps = device_time ? StampClock::sensor : StampClock::host_arrival;
  if (ptp.has_ptp && ptp.enabled) {
    clock.source = ClockSource::ptp;
    clock.offset_from_master_ns = ptp.offset_from_master_ns;
    if (ptp.grandmaster) clock.grandmaster = clock_identity_text(*ptp.grandmaster);
    ptp_state(ptp, clock);
    if (!device_time) {  // the camera's PTP state says nothing of host receive stamps
      clock.source = ClockSource::host;
      clock.state = ClockState::unknown;
      clock.verdict = ClockVerdict::unknown;
      clock.problem.clear();
    }
    return clock;
  }
  if (!device_time) {
    clock.source = ClockSource::host;  // receive time; the host's synchronisation is judged apart
    return clock;
  }
  clock.source = ClockSource::free_running;
  clock.state = ClockState::free_running;
  set_problem(clock, ptp.has_ptp
                         ? "the frames carry the camera's clock with PTP off: it counts from power-up, not the time "
                           "of day; enable PTP on the camera (PtpEnable) or drop --device-timestamps"
                         : "the frames carry the camera's clock, which has no PTP features: it counts from power-up, "
                           "not the time of day; drop --device-timestamps to stamp with the host receive time");
  return clock;
}

}  // namespace sim::camera
