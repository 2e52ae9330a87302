// SPDX-License-Identifier: Apache-2.0
// The per-packet clock check. add() runs on the receive path: a few compares and stores per
// packet, a decimated sample every 4 ms and, once a second, the median of that second's
// samples (at most 256, on a fixed array). judge() runs about once a second off the frame path
// and may sort and format.
#include "sim/timing/clock_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <optional>
#include <string>

namespace sim::timing {
namespace {

constexpr std::int64_t kSecondNs = 1'000'000'000;
constexpr std::int64_t kMinuteNs = 60 * kSecondNs;
constexpr std::int64_t kHourNs = 60 * kMinuteNs;
constexpr std::int64_t kDayNs = 24 * kHourNs;
// TAI − UTC since 2017-01-01, as a PTP master announces it (currentUtcOffset 37).
constexpr std::int64_t kTaiUtcNs = 37 * kSecondNs;
// GPS time − UTC (the 18 leap seconds since 1980): a GNSS receiver's time not turned into UTC.
constexpr std::int64_t kGpsUtcNs = 18 * kSecondNs;
// A sensor time before 2000-01-01 is no calendar date: the clock counts from power-on.
constexpr std::int64_t kYear2000Ns = 946'684'800LL * kSecondNs;
// A packet stamped this much before the one before it went backwards: one sensor's packets leave
// in order, and a link reorders them by far less.
constexpr std::int64_t kBackwardsNs = 1'000'000;
// Steps, stamps going backwards and stamps in the future are told for this long after the last.
constexpr std::int64_t kRecentNs = 60 * kSecondNs;
// The median over the samples of the last second; the drift over at least 10 s of seconds.
constexpr std::int64_t kMedianWindowNs = kSecondNs;
constexpr std::int64_t kDriftMinSpanNs = 10 * kSecondNs;
constexpr std::size_t kDriftMinSeconds = 5;

std::int64_t saturating_sub(std::int64_t a, std::int64_t b) noexcept {
  std::int64_t out = 0;
  if (!__builtin_sub_overflow(a, b, &out)) return out;
  return b < 0 ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
}

// |x| without the overflow of std::abs(INT64_MIN).
std::uint64_t magnitude(std::int64_t x) noexcept {
  return x < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(x) : static_cast<std::uint64_t>(x);
}
bool beyond(std::int64_t x, std::int64_t limit) noexcept {
  return magnitude(x) > static_cast<std::uint64_t>(std::max<std::int64_t>(limit, 0));
}

// The lower median of `n` values, reordering them.
std::int64_t median_of(std::int64_t* values, std::size_t n) noexcept {
  const std::size_t middle = (n - 1) / 2;
  std::nth_element(values, values + middle, values + n);
  return values[middle];
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

// A duration for people, unsigned: "12 µs", "37.0 s", "3.0 h", "2.5 years".
std::string duration_text(std::uint64_t ns) {
  constexpr auto most = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  return human_duration(static_cast<std::int64_t>(std::min(ns, most)));
}
std::string signed_duration(std::int64_t ns) {
  std::string text = ns < 0 ? "-" : "+";  // appended, not prepended: GCC 12 warns (-Wrestrict)
  return text += duration_text(magnitude(ns));
}
// "2.5 years behind", "37.0 s ahead of"
std::string ahead_or_behind(std::int64_t offset_ns) {
  return duration_text(magnitude(offset_ns)) + (offset_ns < 0 ? " behind" : " ahead of");
}

// "2026-11-27 14:03:12 UTC"
std::string utc_text(std::int64_t ns) {
  const std::time_t seconds = static_cast<std::time_t>(ns / kSecondNs - (ns % kSecondNs < 0 ? 1 : 0));
  std::tm tm{};
  if (gmtime_r(&seconds, &tm) == nullptr) return "an unreadable time";
  char text[48];
  if (std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm) == 0) return "an unreadable time";
  return text;
}

// How far `offset` lies from the nearest whole multiple of `unit`, and that multiple.
struct Whole {
  std::int64_t count;
  std::uint64_t off_by;
};
Whole nearest_whole(std::int64_t offset, std::int64_t unit) noexcept {
  const std::int64_t count = static_cast<std::int64_t>(std::llround(static_cast<double>(offset) / static_cast<double>(unit)));
  const double rest = static_cast<double>(offset) - static_cast<double>(count) * static_cast<double>(unit);
  return {count, static_cast<std::uint64_t>(std::fabs(rest))};
}

// A finding: how bad, and its sentence. The first found (in the order judge() looks) speaks;
// the verdict is the worst of all.
struct Finding {
  ClockVerdict verdict;
  std::string sentence;
};

// The sentence for an offset beyond tolerance.offset_error_ns, by the shape of its size.
std::string offset_sentence(std::int64_t offset, const std::string& against) {
  const std::string off = ahead_or_behind(offset) + " " + against;
  if (static_cast<double>(magnitude(offset)) >= 180.0 * static_cast<double>(kDayNs)) {
    return "The sensor's clock is " + off +
           ": it was never synchronised (a free-running calendar, or PTP or GPS not locked); "
           "synchronise it or stamp with host time.";
  }
  const Whole hours = nearest_whole(offset, kHourNs);
  if (hours.count != 0 && hours.off_by <= 2'000'000'000 && magnitude(offset) >= 30 * kMinuteNs) {
    return "The sensor's clock is " + std::to_string(magnitude(hours.count)) + " h" +
           (offset < 0 ? " behind " : " ahead of ") + against +
           ": a time zone or daylight-saving offset, or a Velodyne without PPS counting the wrong "
           "hour; keep the sensor's clock in UTC and give it PPS.";
  }
  const Whole gps = nearest_whole(offset, kGpsUtcNs);
  if (gps.count == 1 && gps.off_by <= 500'000'000) {
    return "The sensor's clock is 18 s ahead of " + against +
           ": GPS time against UTC (the 18 leap seconds); have the receiver or the sensor apply "
           "the leap seconds.";
  }
  const Whole seconds = nearest_whole(offset, kSecondNs);
  if (seconds.off_by <= 20'000'000) {
    return "The sensor's clock is " + std::to_string(magnitude(seconds.count)) + " s" +
           (offset < 0 ? " behind " : " ahead of ") + against +
           ", whole seconds: a leap second or an offset set by hand; synchronise it (PTP, or GPS "
           "and PPS).";
  }
  if (offset > 0) {
    return "The sensor's stamps lie " + duration_text(magnitude(offset)) +
           " in the future of their arrival on " + against +
           ": its clock runs ahead; synchronise it (PTP, or GPS and PPS).";
  }
  return "The sensor's stamps are " + off +
         ": its clock is not synchronised, or packets wait long before they are taken; "
         "synchronise it (PTP, or GPS and PPS).";
}

// What the sensor says of its own synchronisation, when that alone is a warning.
std::optional<Finding> state_finding(const ClockStatus& reported) {
  if (reported.state == ClockState::free_running || reported.source == ClockSource::free_running) {
    return Finding{ClockVerdict::warn,
                   "The sensor reports a free-running clock (no time source): its stamps drift "
                   "from the host's; synchronise it (PTP, or GPS and PPS)."};
  }
  if (reported.state == ClockState::holdover) {
    return Finding{ClockVerdict::warn,
                   "The sensor lost its time source and is in holdover: its stamps drift from now "
                   "on; check the grandmaster or GPS and the cabling."};
  }
  if (reported.state == ClockState::acquiring) {
    return Finding{ClockVerdict::warn,
                   "The sensor's clock is still acquiring its time source, not locked yet; wait "
                   "for the lock (PTP takes up to a minute) before trusting its stamps."};
  }
  return std::nullopt;
}

// Cut to at most `size` bytes without splitting a UTF-8 character.
void cut_utf8(std::string& text, std::size_t size) {
  if (text.size() <= size) return;
  std::size_t end = size;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  text.resize(end);
}

}  // namespace

void ClockCheck::Event::add(std::int64_t size, std::int64_t arrival, std::int64_t sensor) noexcept {
  ++count;
  size_ns = size;
  if (!recent || magnitude(size) > magnitude(worst_ns)) worst_ns = size;
  arrival_ns = arrival;
  sensor_ns = sensor;
  recent = true;
}

ClockCheck::ClockCheck(ClockTolerance tolerance) : tolerance_(tolerance) {}

void ClockCheck::add(std::int64_t sensor_ns, std::int64_t arrival_ns) noexcept {
  ++packets_;
  const std::int64_t offset = saturating_sub(sensor_ns, arrival_ns);
  if (have_last_ && sensor_ns < saturating_sub(last_sensor_ns_, kBackwardsNs)) {
    backwards_.add(saturating_sub(sensor_ns, last_sensor_ns_), arrival_ns, sensor_ns);
  }
  if (offset > tolerance_.future_ns) future_.add(offset, arrival_ns, sensor_ns);
  if (have_reference_ && pending_step_arrival_ns_ == 0 &&
      beyond(saturating_sub(offset, reference_offset_ns_), tolerance_.step_ns)) {
    pending_step_arrival_ns_ = arrival_ns;  // where a step would have begun
    pending_step_sensor_ns_ = sensor_ns;
  }
  have_last_ = true;
  last_sensor_ns_ = sensor_ns;
  last_arrival_ns_ = arrival_ns;

  // Decimated: a few samples per 10 ms are plenty for a median and keep a second in the ring.
  if (sample_count_ != 0 && arrival_ns >= last_sample_ns_ &&
      saturating_sub(arrival_ns, last_sample_ns_) < kSamplePeriodNs) {
    return;
  }
  last_sample_ns_ = arrival_ns;
  samples_[sample_next_] = Sample{arrival_ns, offset};
  sample_next_ = (sample_next_ + 1) % kSamples;
  sample_count_ = std::min(sample_count_ + 1, kSamples);

  if (second_count_ != 0 && (arrival_ns < second_start_ns_ ||
                             saturating_sub(arrival_ns, second_start_ns_) >= kSecondNs)) {
    close_second();
  }
  if (second_count_ == 0) second_start_ns_ = arrival_ns;
  if (second_count_ < second_offsets_.size()) second_offsets_[second_count_++] = offset;
  second_last_ns_ = arrival_ns;
}

// The median of the second just collected: a step when it left the last one by more than
// tolerance.step_ns (the drift is then measured afresh), and a point for the drift.
void ClockCheck::close_second() noexcept {
  const std::int64_t median = median_of(second_offsets_.data(), second_count_);
  if (have_reference_) {
    const std::int64_t jump = saturating_sub(median, reference_offset_ns_);
    if (beyond(jump, tolerance_.step_ns)) {
      const bool located = pending_step_arrival_ns_ != 0;
      steps_.add(jump, located ? pending_step_arrival_ns_ : second_start_ns_,
                 located ? pending_step_sensor_ns_ : 0);
      second_total_ = 0;
    }
  }
  reference_offset_ns_ = median;
  have_reference_ = true;
  const std::int64_t middle = second_start_ns_ + saturating_sub(second_last_ns_, second_start_ns_) / 2;
  seconds_[second_total_ % kSeconds] = Second{middle, median};
  ++second_total_;
  second_count_ = 0;
  pending_step_arrival_ns_ = 0;
}

void ClockCheck::restart() noexcept {
  // Hold the last measurement until the new pass has one of its own.
  ClockStatus none;
  const ClockStatus last = measure(none);
  if (last.offset_to_host_ns) {
    have_held_ = true;
    held_offset_ns_ = *last.offset_to_host_ns;
    held_spread_ns_ = last.spread_ns;
    held_sensor_ns_ = last_sensor_ns_;
  }
  have_last_ = false;
  sample_count_ = 0;
  sample_next_ = 0;
  second_count_ = 0;
  second_total_ = 0;
  have_reference_ = false;
  pending_step_arrival_ns_ = 0;
  steps_.recent = false;
  backwards_.recent = false;
  future_.recent = false;
}

// The offset (median of the last second's samples), its spread and the drift, into `out`.
ClockStatus ClockCheck::measure(const ClockStatus& reported) const {
  ClockStatus out = reported;
  out.offset_to_host_ns.reset();
  out.spread_ns = 0;
  out.drift_ppm = 0.0;
  if (sample_count_ == 0) {
    if (have_held_) {
      out.offset_to_host_ns = held_offset_ns_;
      out.spread_ns = held_spread_ns_;
    }
    return out;
  }
  const std::size_t newest_index = (sample_next_ + kSamples - 1) % kSamples;
  const std::int64_t newest = samples_[newest_index].arrival_ns;
  std::array<std::int64_t, kSamples> recent{};
  std::size_t n = 0;
  for (std::size_t i = 0; i < sample_count_; ++i) {
    const Sample& s = samples_[(newest_index + kSamples - i) % kSamples];
    if (s.arrival_ns > newest || saturating_sub(newest, s.arrival_ns) > kMedianWindowNs) break;
    recent[n++] = s.offset_ns;
  }
  const std::int64_t median = median_of(recent.data(), n);
  for (std::size_t i = 0; i < n; ++i) recent[i] = static_cast<std::int64_t>(
      std::min<std::uint64_t>(magnitude(saturating_sub(recent[i], median)),
                              static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())));
  const std::size_t p90 = std::min(n - 1, (n * 9) / 10);
  std::nth_element(recent.begin(), recent.begin() + static_cast<std::ptrdiff_t>(p90),
                   recent.begin() + static_cast<std::ptrdiff_t>(n));
  out.offset_to_host_ns = median;
  out.spread_ns = recent[p90];

  // Least squares of the per-second medians against arrival, relative to the first (doubles:
  // differences of 1e18-sized numbers stay exact enough at the ns scale over a minute).
  const std::size_t count = std::min(second_total_, kSeconds);
  if (count >= kDriftMinSeconds) {
    const Second& first = seconds_[(second_total_ - count) % kSeconds];
    const Second& last = seconds_[(second_total_ - 1) % kSeconds];
    if (saturating_sub(last.arrival_ns, first.arrival_ns) >= kDriftMinSpanNs) {
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      for (std::size_t i = second_total_ - count; i < second_total_; ++i) {
        const Second& s = seconds_[i % kSeconds];
        const double x = static_cast<double>(saturating_sub(s.arrival_ns, first.arrival_ns));
        const double y = static_cast<double>(saturating_sub(s.offset_ns, first.offset_ns));
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
      }
      const double k = static_cast<double>(count);
      const double denominator = k * sxx - sx * sx;
      if (denominator > 0) {
        const double slope = (k * sxy - sx * sy) / denominator;
        if (std::isfinite(slope)) out.drift_ppm = slope * 1e6;
      }
    }
  }
  return out;
}

struct ClockCheck::Findings {
  std::optional<Finding> first;
  ClockVerdict worst = ClockVerdict::unknown;
  void found(ClockVerdict verdict, std::string sentence) {
    worst = std::max(worst, verdict);
    if (!first) first = Finding{verdict, std::move(sentence)};
  }
};

bool ClockCheck::recent(const Event& e) const noexcept {
  return e.recent && saturating_sub(last_arrival_ns_, e.arrival_ns) <= kRecentNs;
}

void ClockCheck::judge_offset(const ClockStatus& out, const ClockStatus& reported, const ClockStatus& host,
                              const std::string& against, Findings& findings) const {
  const bool host_stamps = reported.stamps == StampClock::host_arrival;
  const std::int64_t latest_sensor = sample_count_ != 0 || !have_held_ ? last_sensor_ns_ : held_sensor_ns_;
  const std::int64_t offset = *out.offset_to_host_ns;
  const std::string off = ahead_or_behind(offset) + " " + against;
  const Whole tai = nearest_whole(offset, kTaiUtcNs);
  const bool is_tai = (tai.count == 1 || tai.count == -1) && tai.off_by <= 500'000'000;
  if (is_tai && tai.count == 1) {
    findings.found(ClockVerdict::error,
                   "The sensor's clock is 37 s ahead of " + against + " (" + duration_text(magnitude(offset)) +
                       "): TAI (the PTP timescale) against UTC; set the UTC offset on the grandmaster, or "
                       "correct it in the driver (sim_lidar_ouster --tai-correction auto) or stamp with "
                       "host time (--stamp-fallback host).");
  } else if (is_tai) {
    findings.found(ClockVerdict::error,
                   "The sensor's clock is 37 s behind " + against + " (" + duration_text(magnitude(offset)) +
                       "): a TAI-to-UTC correction applied to a clock already in UTC, or a host keeping "
                       "TAI; drop the correction, or set the host's UTC offset (phc2sys -O).");
  } else if (latest_sensor < kYear2000Ns && beyond(offset, tolerance_.offset_error_ns)) {
    findings.found(ClockVerdict::error,
                   "The sensor's stamps are in 1970 (time since power-on, " +
                       duration_text(magnitude(latest_sensor)) +
                       "): its clock was never set; synchronise it (PTP, or GPS and PPS) or stamp with "
                       "host time.");
  } else if (reported.state == ClockState::locked && host.state == ClockState::locked &&
             beyond(offset, tolerance_.offset_error_ns)) {
    findings.found(ClockVerdict::error,
                   "The sensor says its clock is locked but its stamps are " + off +
                       ", which is synchronised too: they follow different grandmasters or PTP domains; "
                       "put both on the same grandmaster and domain.");
  }
  if (recent(steps_)) {
    std::string sentence = "The sensor's clock stepped by " + signed_duration(steps_.size_ns) + " at " +
                           utc_text(steps_.arrival_ns);
    if (beyond(offset, tolerance_.offset_ok_ns)) sentence += " and its stamps are now " + off;
    findings.found(ClockVerdict::warn, sentence + "; look for a resynchronisation (PTP, GPS), a clock set "
                                                  "by hand or a sensor restart.");
  }
  if (beyond(offset, tolerance_.offset_error_ns)) {
    findings.found(ClockVerdict::error, offset_sentence(offset, against));
  } else if (beyond(offset, tolerance_.offset_ok_ns)) {
    findings.found(ClockVerdict::warn,
                   "The sensor's stamps are " + off + ", more than the " +
                       duration_text(magnitude(tolerance_.offset_ok_ns)) +
                       " tolerated; synchronise its clock, or widen the tolerance if this is the sensor's "
                       "own latency.");
  }
  if (!host_stamps && std::fabs(out.drift_ppm) > tolerance_.drift_warn_ppm) {
    findings.found(ClockVerdict::warn,
                   "The sensor's clock drifts " + std::string(out.drift_ppm < 0 ? "-" : "+") +
                       fixed(std::fabs(out.drift_ppm), 0) + " ppm against " + against + " (" +
                       duration_text(static_cast<std::uint64_t>(std::fabs(out.drift_ppm) * 3.6e6)) +
                       " an hour): a free-running clock; synchronise it (PTP, or GPS and PPS).");
  }
}

void ClockCheck::judge_stamps(const ClockStatus& out, const ClockStatus& reported, const std::string& against,
                              Findings& findings) const {
  const bool host_stamps = reported.stamps == StampClock::host_arrival;
  if (!host_stamps && beyond(out.spread_ns, tolerance_.spread_warn_ns)) {
    findings.found(ClockVerdict::warn,
                   "The sensor's stamps scatter by " + duration_text(magnitude(out.spread_ns)) +
                       " around their offset to " + against + ", more than the " +
                       duration_text(magnitude(tolerance_.spread_warn_ns)) +
                       " tolerated; look for a congested network or a busy host, or widen the tolerance.");
  }
  if (recent(future_)) {
    findings.found(ClockVerdict::warn,
                   "Some of the sensor's stamps lie in the future, up to " +
                       duration_text(magnitude(future_.worst_ns)) + " ahead of their arrival on " + against +
                       ": its clock jumps ahead now and then; check its synchronisation.");
  }
  if (recent(backwards_)) {
    findings.found(ClockVerdict::warn,
                   "The sensor's stamps went backwards (" + std::to_string(backwards_.count) +
                       " times, by up to " + duration_text(magnitude(backwards_.worst_ns)) +
                       "): its clock was set back or its packets come from two clocks; check its "
                       "synchronisation.");
  }
}

ClockStatus ClockCheck::judge(const ClockStatus& reported, const ClockStatus& host,
                              std::int64_t now_realtime_ns) {
  ClockStatus out = measure(reported);
  out.steps = static_cast<std::uint32_t>(std::min<std::uint64_t>(steps_.count, UINT32_MAX));
  out.last_step_ns = steps_.size_ns;
  out.packets_measured = packets_;
  out.measured_ns = now_realtime_ns;
  out.verdict = ClockVerdict::unknown;
  out.problem.clear();

  // The order of the findings is the order of the sentences: the first one found is the problem.
  const std::string against = reported.source == ClockSource::replayed ? "the recording host" : "this host";
  Findings findings;
  if (out.offset_to_host_ns) judge_offset(out, reported, host, against, findings);
  if (auto state = state_finding(reported)) findings.found(state->verdict, std::move(state->sentence));
  // What the report itself warns of (an unreadable NMEA sentence, a clock the camera cannot
  // name, a sensor that did not answer) stands beside what the stamps show.
  if (reported.verdict >= ClockVerdict::warn && !reported.problem.empty()) {
    findings.found(reported.verdict, reported.problem);
  }
  if (out.offset_to_host_ns) {
    judge_stamps(out, reported, against, findings);
    if (!findings.first) {
      out.verdict = ClockVerdict::ok;
      return out;
    }
  }
  if (findings.first) {
    out.verdict = findings.worst;
    out.problem = findings.first->sentence;
    cut_utf8(out.problem, ClockStatus::kMaxProblem);
  }
  return out;
}

}  // namespace sim::timing
