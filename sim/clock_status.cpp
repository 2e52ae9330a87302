// SPDX-License-Identifier: Apache-2.0
#include "sim/clock_status.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

namespace sim {

namespace {

template <typename Enum, std::size_t N>
const char* name_of(Enum value, const char* const (&names)[N]) noexcept {
  const auto index = static_cast<std::size_t>(value);
  return index < N ? names[index] : "invalid";
}

constexpr const char* kSourceNames[] = {"unknown",  "host",       "ptp",          "gptp",
                                        "pps_nmea", "sync_pulse", "free_running", "replayed"};
constexpr const char* kStateNames[] = {"unknown", "locked", "acquiring", "holdover", "free_running"};
constexpr const char* kVerdictNames[] = {"unknown", "ok", "warn", "error"};
constexpr const char* kStampNames[] = {"unknown", "sensor", "sensor_tai_corrected", "host_arrival"};

template <typename Enum, std::size_t N>
bool in_range(Enum value, const char* const (&)[N]) noexcept {
  return static_cast<std::size_t>(value) < N;
}

// A text a sensor or daemon may have put in the record: no control characters.
bool printable_text(const std::string& text) noexcept {
  for (const char ch : text) {
    if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) return false;
  }
  return true;
}

std::string signed_duration(std::int64_t ns) {
  std::string text = human_duration(ns);
  if (ns > 0) text.insert(text.begin(), '+');
  return text;
}

}  // namespace

const char* to_string(ClockSource source) noexcept { return name_of(source, kSourceNames); }
const char* to_string(ClockState state) noexcept { return name_of(state, kStateNames); }
const char* to_string(ClockVerdict verdict) noexcept { return name_of(verdict, kVerdictNames); }
const char* to_string(StampClock clock) noexcept { return name_of(clock, kStampNames); }

bool operator==(const ClockStatus& a, const ClockStatus& b) noexcept {
  return a.source == b.source && a.state == b.state && a.ptp_domain == b.ptp_domain &&
         a.offset_from_master_ns == b.offset_from_master_ns && a.path_delay_ns == b.path_delay_ns &&
         a.grandmaster == b.grandmaster && a.utc_offset_s == b.utc_offset_s &&
         a.ptp_timescale == b.ptp_timescale && a.tai_correction_ns == b.tai_correction_ns &&
         a.reported_ns == b.reported_ns && a.offset_to_host_ns == b.offset_to_host_ns &&
         a.spread_ns == b.spread_ns && a.drift_ppm == b.drift_ppm && a.steps == b.steps &&
         a.last_step_ns == b.last_step_ns && a.packets_measured == b.packets_measured &&
         a.measured_ns == b.measured_ns && a.verdict == b.verdict && a.problem == b.problem &&
         a.stamps == b.stamps;
}

std::string human_duration(std::int64_t ns) {
  // Magnitude in double: |INT64_MIN| does not fit an int64.
  const double magnitude = std::fabs(static_cast<double>(ns));
  const char* sign = ns < 0 ? "-" : "";
  constexpr double kSecond = 1e9, kHour = 3600 * kSecond, kDay = 24 * kHour, kYear = 365.25 * kDay;
  char text[48];
  if (magnitude < 1e3) {
    std::snprintf(text, sizeof text, "%s%.0f ns", sign, magnitude);
  } else if (magnitude < 1e6) {
    std::snprintf(text, sizeof text, "%s%.0f µs", sign, magnitude / 1e3);
  } else if (magnitude < kSecond) {
    std::snprintf(text, sizeof text, "%s%.1f ms", sign, magnitude / 1e6);
  } else if (magnitude < 600 * kSecond) {
    std::snprintf(text, sizeof text, "%s%.1f s", sign, magnitude / kSecond);
  } else if (magnitude < kHour) {
    std::snprintf(text, sizeof text, "%s%.0f min", sign, magnitude / (60 * kSecond));
  } else if (magnitude < 2 * kDay) {
    std::snprintf(text, sizeof text, "%s%.1f h", sign, magnitude / kHour);
  } else if (magnitude < kYear) {
    std::snprintf(text, sizeof text, "%s%.1f days", sign, magnitude / kDay);
  } else {
    std::snprintf(text, sizeof text, "%s%.1f years", sign, magnitude / kYear);
  }
  return text;
}

std::string summary(const ClockStatus& c) {
  std::string line = std::string(to_string(c.source)) + " " + to_string(c.state);
  if (c.ptp_domain >= 0) line += ", domain " + std::to_string(c.ptp_domain);
  if (!c.grandmaster.empty()) line += ", grandmaster " + c.grandmaster;
  if (c.offset_from_master_ns) line += ", offset from master " + signed_duration(*c.offset_from_master_ns);
  if (c.tai_correction_ns != 0) line += ", TAI corrected by " + human_duration(c.tai_correction_ns);
  if (c.offset_to_host_ns) {
    line += ", offset to host " + signed_duration(*c.offset_to_host_ns) + " ±" + human_duration(c.spread_ns);
  } else {
    line += ", offset to host not measured yet";
  }
  if (c.drift_ppm != 0.0) {
    char drift[32];
    std::snprintf(drift, sizeof drift, ", drift %+.1f ppm", c.drift_ppm);
    line += drift;
  }
  if (c.steps != 0) line += ", " + std::to_string(c.steps) + (c.steps == 1 ? " step" : " steps");
  line += std::string(": ") + to_string(c.verdict);
  if (!c.problem.empty()) line += ": " + c.problem;
  return line;
}

std::string clock_status_problem(const ClockStatus& c) {
  if (!in_range(c.source, kSourceNames)) return "the clock source " + std::to_string(static_cast<std::uint32_t>(c.source)) + " is unknown";
  if (!in_range(c.state, kStateNames)) return "the clock state " + std::to_string(static_cast<std::uint32_t>(c.state)) + " is unknown";
  if (!in_range(c.verdict, kVerdictNames)) return "the clock verdict " + std::to_string(static_cast<std::uint32_t>(c.verdict)) + " is unknown";
  if (!in_range(c.stamps, kStampNames)) return "the stamp clock " + std::to_string(static_cast<std::uint32_t>(c.stamps)) + " is unknown";
  if (c.ptp_domain < -1 || c.ptp_domain > 255) return "the PTP domain " + std::to_string(c.ptp_domain) + " is outside -1..255";
  if (c.grandmaster.size() > ClockStatus::kMaxGrandmaster || !printable_text(c.grandmaster)) {
    return "the grandmaster identity must be at most " + std::to_string(ClockStatus::kMaxGrandmaster) +
           " printable bytes (pass it through sim::sensor_text)";
  }
  if (c.problem.size() > ClockStatus::kMaxProblem || !printable_text(c.problem)) {
    return "the clock's problem sentence must be at most " + std::to_string(ClockStatus::kMaxProblem) +
           " printable bytes (pass it through sim::sensor_text)";
  }
  if (!std::isfinite(c.drift_ppm)) return "the clock's drift is not a finite number of ppm";
  return {};
}

std::string pairing_problem(std::string_view first_name, const ClockStatus& first,
                            std::string_view second_name, const ClockStatus& second,
                            std::int64_t tolerance_ns) {
  const std::string a(first_name), b(second_name);
  for (const auto& [name, clock] : {std::pair{&a, &first}, std::pair{&b, &second}}) {
    if (clock->verdict == ClockVerdict::error) {
      return *name + "'s clock is in error (" + (clock->problem.empty() ? "no reason given" : clock->problem) +
             "), so its stamps cannot be paired with " + (name == &a ? b : a) + "'s";
    }
  }
  if (!first.grandmaster.empty() && !second.grandmaster.empty() && first.grandmaster != second.grandmaster) {
    return a + " and " + b + " follow different PTP grandmasters (" + first.grandmaster + ", " +
           second.grandmaster + "): put both on one grandmaster before pairing their stamps";
  }
  const auto is_ptp = [](const ClockStatus& c) {
    return c.source == ClockSource::ptp || c.source == ClockSource::gptp;
  };
  if (is_ptp(first) && is_ptp(second) && first.ptp_domain >= 0 && second.ptp_domain >= 0 &&
      first.ptp_domain != second.ptp_domain) {
    return a + " and " + b + " are in different PTP domains (" + std::to_string(first.ptp_domain) + ", " +
           std::to_string(second.ptp_domain) + "): put both in one domain before pairing their stamps";
  }
  if (first.offset_to_host_ns && second.offset_to_host_ns) {
    // In double: two offsets near the int64 limits must not overflow their difference.
    const double apart = static_cast<double>(*first.offset_to_host_ns) - static_cast<double>(*second.offset_to_host_ns);
    if (std::fabs(apart) > static_cast<double>(tolerance_ns)) {
      return "the clocks of " + a + " and " + b + " disagree by " +
             human_duration(static_cast<std::int64_t>(std::min(std::fabs(apart), 9.2e18))) + " (" + a + " " +
             signed_duration(*first.offset_to_host_ns) + ", " + b + " " +
             signed_duration(*second.offset_to_host_ns) + " against the host), beyond the tolerance of " +
             human_duration(tolerance_ns);
    }
  }
  return {};
}

}  // namespace sim
