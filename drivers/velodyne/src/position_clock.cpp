// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/position_clock.hpp"

#include <string>

namespace sim::velodyne {
namespace {

ClockState state_of(const PositionReport& report) noexcept {
  switch (report.pps) {
    case PpsState::locked: return ClockState::locked;
    case PpsState::synchronizing: return ClockState::acquiring;
    case PpsState::absent: return ClockState::free_running;  // the top-of-hour counter free-runs
    case PpsState::error: return ClockState::holdover;
    case PpsState::unknown:  // HDL-32E/64E: no PPS state; the NMEA fix is all there is
      return report.nmea == NmeaStatus::fix ? ClockState::locked : ClockState::free_running;
    case PpsState::invalid: return ClockState::unknown;
  }
  return ClockState::unknown;
}

// The top-of-hour counter minus the NMEA time's minutes and seconds, in seconds within ±30 min
// (both count within the hour), when the sentence has a time.
std::optional<std::int64_t> nmea_disagreement_s(const PositionReport& report) noexcept {
  if (!report.nmea_second_of_hour) return std::nullopt;
  std::int64_t difference = std::int64_t{report.timestamp_us} / 1'000'000 - *report.nmea_second_of_hour;
  difference %= 3600;
  if (difference > 1800) difference -= 3600;
  if (difference <= -1800) difference += 3600;
  return difference;
}

// What the PPS state alone says is wrong; "" when nothing.
std::string pps_problem(const PositionReport& report) {
  switch (report.pps) {
    case PpsState::invalid:
      return "the position packet's PPS byte is " + std::to_string(report.pps_byte) +
             ", none of 0-3 (absent, synchronizing, locked, error): a corrupt packet or another device on the "
             "position port, so the sensor's clock state is unknown";
    case PpsState::error:
      return "the sensor reports a PPS error: its clock holds over from the last pulse and drifts; check the "
             "GNSS receiver's PPS signal and cable";
    case PpsState::absent:
      return "the sensor sees no PPS: its top-of-hour counter free-runs, so its stamps drift and can be up to "
             "30 minutes off; connect the GNSS receiver's PPS output to the sensor";
    case PpsState::synchronizing:
      return "the sensor is synchronizing to its PPS input: its stamps are not to be trusted until it reports "
             "locked";
    case PpsState::locked:
    case PpsState::unknown: return {};
  }
  return {};
}

// What the NMEA sentence says is wrong (PPS locked or not reported); "" when nothing.
std::string nmea_problem(const PositionReport& report) {
  switch (report.nmea) {
    case NmeaStatus::unreadable:
      return "the position packet's NMEA sentence is unreadable (no $GPRMC or $GPGGA with a good checksum), so "
             "the sensor may take a wrong time of day; check the GNSS receiver's baud rate and sentence type";
    case NmeaStatus::none:
      return "the sensor gets no NMEA sentence: nothing sets its time of day; connect the GNSS receiver's NMEA "
             "output to the sensor";
    case NmeaStatus::no_fix:
      return "the GNSS receiver reports no fix in its NMEA sentence: the time of day it sends the sensor may be "
             "wrong; give its antenna a view of the sky";
    case NmeaStatus::fix: break;
  }
  const auto disagreement = nmea_disagreement_s(report);
  if (disagreement && (*disagreement > max_nmea_disagreement_s || *disagreement < -max_nmea_disagreement_s)) {
    return "the sensor's top-of-hour counter is " + std::to_string(*disagreement) +
           " s from its NMEA time although PPS is locked, so its stamps are off by that much; check the "
           "GNSS receiver's NMEA output";
  }
  return {};
}

}  // namespace

ClockStatus clock_status_of(const PositionReport& report, std::int64_t reported_ns) {
  ClockStatus clock;
  clock.source = ClockSource::pps_nmea;
  clock.state = state_of(report);
  clock.stamps = StampClock::sensor;
  clock.reported_ns = reported_ns;
  std::string problem = pps_problem(report);
  if (problem.empty()) problem = nmea_problem(report);
  if (!problem.empty()) {
    clock.verdict = ClockVerdict::warn;
    clock.problem = problem.substr(0, ClockStatus::kMaxProblem);
  }
  return clock;
}

}  // namespace sim::velodyne
