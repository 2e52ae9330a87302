// SPDX-License-Identifier: Apache-2.0
// A stream's clock as data: where its stamps come from, what the sensor (or the host) reports
// about its synchronisation, what the driver measured by comparing each packet's sensor time with
// its arrival on this host, and the verdict on all of it.
//
// The writer sets it (Writer::set_clock), usually once a second from a driver's clock watch, off
// the frame path; readers get it with Reader::clock() and notice a change through
// FrameInfo::clock_generation without reopening, as they notice a new sensor description. It
// lives in the region's header page beside the sensor description; publishing and reading a frame
// cost nothing more for it. docs/protocol.md ("Clock record") has the format, README "Time" what
// each verdict means.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace sim {

// Where a clock gets its time from.
enum class ClockSource : std::uint32_t {
  unknown = 0,
  host = 1,          // the host's CLOCK_REALTIME (stamps taken at arrival)
  ptp = 2,           // IEEE 1588 PTP (ClockStatus::ptp_domain says which domain)
  gptp = 3,          // IEEE 802.1AS (gPTP)
  pps_nmea = 4,      // a GNSS receiver's pulse per second and its NMEA time
  sync_pulse = 5,    // a sync pulse input without NMEA (seconds counted from power-on)
  free_running = 6,  // the sensor's own oscillator, never set from outside
  replayed = 7,      // a recording's stamps, as recorded (the recording host's clock judges them)
};
const char* to_string(ClockSource source) noexcept;  // "unknown", "host", "ptp", "gptp", …

// What the clock's synchronisation says of itself (or, for `host`, the host's daemon).
enum class ClockState : std::uint32_t {
  unknown = 0,       // nobody reported a state
  locked = 1,        // synchronised to its source within the source's own threshold
  acquiring = 2,     // listening or tracking: not locked yet
  holdover = 3,      // lost its source (unlocked, frozen, holdover): drifting from now on
  free_running = 4,  // has no source at all
};
const char* to_string(ClockState state) noexcept;  // "unknown", "locked", "acquiring", …

// The verdict on a clock: what a launch script and a fusion node decide by.
enum class ClockVerdict : std::uint32_t {
  unknown = 0,  // not measured yet, and nothing reported says it is wrong
  ok = 1,
  warn = 2,     // usable, with care (acquiring, a step seen, wide spread, drift)
  error = 3,    // its stamps cannot be paired with host-time streams (seconds/hours/years off…)
};
const char* to_string(ClockVerdict verdict) noexcept;  // "unknown", "ok", "warn", "error"

// Which clock a frame's stamp_ns is in (FrameInfo::stamp_clock): what a driver's opt-in fix did.
enum class StampClock : std::uint32_t {
  unknown = 0,
  sensor = 1,                // the sensor's clock as it stamped the data
  sensor_tai_corrected = 2,  // the sensor's clock less ClockStatus::tai_correction_ns (TAI → UTC)
  host_arrival = 3,          // the host's CLOCK_REALTIME at arrival (the sensor clock untrusted)
};
const char* to_string(StampClock clock) noexcept;  // "unknown", "sensor", "sensor_tai_corrected", …

struct ClockStatus {
  static constexpr std::size_t kMaxGrandmaster = 23;  // "xxxxxx.xxxx.xxxxxx" and then some, bytes
  static constexpr std::size_t kMaxProblem = 255;     // the problem sentence, bytes

  // --- Reported: what the sensor (PTC, HTTP, position packets, GenICam) or host daemon says.
  ClockSource source = ClockSource::unknown;
  ClockState state = ClockState::unknown;
  std::int32_t ptp_domain = -1;                       // PTP/gPTP domain; -1 unknown or not PTP
  std::optional<std::int64_t> offset_from_master_ns;  // as reported; nullopt when not
  std::optional<std::int64_t> path_delay_ns;          // mean path delay, as reported
  std::string grandmaster{};  // grandmaster's clock identity as ptp4l prints it; "" unknown
  std::optional<std::int32_t> utc_offset_s;  // TAI − UTC announced by the master (37); nullopt unknown
  bool ptp_timescale = false;                // the master serves the PTP (TAI) timescale
  std::int64_t tai_correction_ns = 0;  // subtracted from the sensor's stamps by the driver; 0 none
  std::int64_t reported_ns = 0;        // CLOCK_REALTIME when the report was read; 0: never

  // --- Measured: each packet's sensor time minus its arrival time on this host (for a replay:
  // its capture time, the recording host's clock), over recent packets.
  std::optional<std::int64_t> offset_to_host_ns;  // median sensor − host, ns; nullopt until measured
  std::int64_t spread_ns = 0;     // how far recent packets lie from the median (90th percentile)
  double drift_ppm = 0.0;         // sensor clock rate against the host's, parts per million
  std::uint32_t steps = 0;        // steps of the sensor clock seen so far
  std::int64_t last_step_ns = 0;  // the size of the last step (signed), 0 before any
  std::uint64_t packets_measured = 0;
  std::int64_t measured_ns = 0;   // CLOCK_REALTIME of the last measurement; 0: never

  // --- Verdict.
  ClockVerdict verdict = ClockVerdict::unknown;
  std::string problem{};  // one sentence saying what is wrong and what to do; "" when ok
  StampClock stamps = StampClock::unknown;  // the clock the frames' stamps are in now
};

bool operator==(const ClockStatus& a, const ClockStatus& b) noexcept;
inline bool operator!=(const ClockStatus& a, const ClockStatus& b) noexcept { return !(a == b); }

// One line for people: "ptp locked, grandmaster 00a069.fffe.0b552d, offset to host +12 µs ±3 µs:
// ok", or "free_running, offset to host −2.5 years: error: <problem>".
std::string summary(const ClockStatus& clock);

// What is wrong with `clock` for storing it (a text too long or not UTF-8 clean, a drift that is
// not finite, an enum out of range), in one sentence; empty when it can be stored.
std::string clock_status_problem(const ClockStatus& clock);

// Why frames of two streams with these clocks cannot be paired by their stamps within
// `tolerance_ns`, in one sentence naming both streams (a clock in error, measured offsets to the
// host that differ by more than the tolerance, different grandmasters or PTP domains), or empty
// when nothing known says they cannot. Unknown clocks are not refused: nothing is known.
std::string pairing_problem(std::string_view first_name, const ClockStatus& first,
                            std::string_view second_name, const ClockStatus& second,
                            std::int64_t tolerance_ns);

// A duration for people: "12 µs", "37.0 s", "1.0 h", "6.4 years" (signed, no '+').
std::string human_duration(std::int64_t ns);

}  // namespace sim
