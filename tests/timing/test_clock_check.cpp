// SPDX-License-Identifier: Apache-2.0
// sim::timing::ClockCheck on made-up packet sequences: each clock failure a user meets gets its
// one sentence, a good clock gets ok, and nothing a sensor sends can break the check.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include "sim/clock_status.hpp"
#include "sim/timing/clock_check.hpp"

namespace {

using sim::ClockSource;
using sim::ClockState;
using sim::ClockStatus;
using sim::ClockVerdict;
using sim::timing::ClockCheck;

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kS = 1'000'000'000;
// 2026-11-27 12:00:00 UTC: the host's arrival clock in these sequences.
constexpr std::int64_t kStart = 1'795'780'800LL * kS;

// A sensor sending `rate` packets a second for `seconds`, each arriving `network` after its
// sensor time plus a deterministic jitter of up to ±200 µs; `offset(t)` is the sensor clock's
// error at host time t since the start (sensor = arrival + offset).
struct Feed {
  double seconds = 20;
  int rate = 1000;
  std::int64_t start = kStart;
  std::function<std::int64_t(std::int64_t)> offset = [](std::int64_t) { return 0; };

  std::int64_t run(ClockCheck& check) const {
    std::uint32_t lcg = 12345;
    const auto packets = static_cast<std::int64_t>(seconds * rate);
    std::int64_t arrival = start;
    for (std::int64_t i = 0; i < packets; ++i) {
      arrival = start + i * (kS / rate);
      lcg = lcg * 1664525u + 1013904223u;
      const std::int64_t jitter = static_cast<std::int64_t>(lcg >> 8) % 400'000 - 200'000;
      check.add(arrival + offset(arrival - start) - 300'000 + jitter, arrival);
    }
    return arrival;
  }
};

ClockStatus judged(ClockCheck& check, const ClockStatus& reported = {}, const ClockStatus& host = {}) {
  return check.judge(reported, host, kStart + 100 * kS);
}

// Every byte sequence a well-formed UTF-8 character (the record stores only such text).
bool utf8_clean(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const auto lead = static_cast<unsigned char>(text[i]);
    const std::size_t length = lead < 0x80 ? 1 : (lead >> 5) == 0x6 ? 2 : (lead >> 4) == 0xE ? 3 : (lead >> 3) == 0x1E ? 4 : 0;
    if (length == 0 || i + length > text.size()) return false;
    for (std::size_t k = 1; k < length; ++k) {
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return false;
    }
    i += length;
  }
  return true;
}

bool says(const ClockStatus& clock, const std::string& words) {
  return clock.problem.find(words) != std::string::npos;
}

TEST(ClockCheck, a_clock_within_a_millisecond_of_the_host_is_ok_and_says_nothing) {
  ClockCheck check;
  Feed{}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::ok) << clock.problem;
  EXPECT_EQ(clock.problem, "");
  ASSERT_TRUE(clock.offset_to_host_ns);
  EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), -300'000.0, 50'000.0);
  EXPECT_LE(clock.spread_ns, 200'000);
  EXPECT_GT(clock.spread_ns, 100'000);
  EXPECT_NEAR(clock.drift_ppm, 0.0, 5.0);
  EXPECT_EQ(clock.steps, 0u);
  EXPECT_EQ(clock.packets_measured, 20'000u);
}

TEST(ClockCheck, nothing_measured_is_unknown_without_a_sentence) {
  ClockCheck check;
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::unknown);
  EXPECT_FALSE(clock.offset_to_host_ns);
  EXPECT_EQ(clock.problem, "");
}

TEST(ClockCheck, the_first_offset_is_there_well_within_two_seconds_of_data) {
  ClockCheck check;
  Feed{.seconds = 0.2, .offset = [](std::int64_t) { return 5 * kS; }}.run(check);
  const ClockStatus clock = judged(check);
  ASSERT_TRUE(clock.offset_to_host_ns);
  EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), 5.0 * kS, 1e6);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
}

TEST(ClockCheck, a_clock_37_s_ahead_is_told_as_tai_against_utc) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t) { return 37 * kS; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "37 s")) << clock.problem;
  EXPECT_TRUE(says(clock, "TAI")) << clock.problem;
  EXPECT_TRUE(says(clock, "ahead")) << clock.problem;
  EXPECT_TRUE(says(clock, "--tai-correction")) << clock.problem;
}

TEST(ClockCheck, a_clock_37_s_behind_is_told_as_a_tai_correction_too_many) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t) { return -37 * kS + 2 * kMs; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "37 s behind")) << clock.problem;
  EXPECT_TRUE(says(clock, "TAI")) << clock.problem;
}

TEST(ClockCheck, a_clock_an_hour_behind_says_1_h) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t) { return -3600 * kS + 1 * kMs; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "1 h behind")) << clock.problem;
  EXPECT_FALSE(says(clock, "TAI")) << clock.problem;
}

TEST(ClockCheck, a_clock_whole_seconds_off_says_how_many) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t) { return 3 * kS; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "3 s ahead")) << clock.problem;
  EXPECT_TRUE(says(clock, "whole seconds")) << clock.problem;
}

TEST(ClockCheck, a_clock_years_behind_says_how_many_years) {
  ClockCheck check;
  constexpr auto years = static_cast<std::int64_t>(2.5 * 365.25 * 86400.0) * kS;
  Feed{.offset = [](std::int64_t) { return -years; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "2.5 years behind")) << clock.problem;
  EXPECT_TRUE(says(clock, "never synchronised")) << clock.problem;
}

TEST(ClockCheck, a_clock_counting_from_power_on_says_1970) {
  ClockCheck check;
  // Up for 3 hours: the sensor's stamps are 1970-01-01 03:00 and on.
  Feed{.offset = [](std::int64_t) { return 3 * 3600 * kS - kStart; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "1970")) << clock.problem;
  EXPECT_TRUE(says(clock, "power-on")) << clock.problem;
  EXPECT_TRUE(says(clock, "3.0 h")) << clock.problem;
}

TEST(ClockCheck, a_2_s_step_is_counted_with_its_size_and_told_with_its_time) {
  ClockCheck check;
  Feed{.seconds = 20, .offset = [](std::int64_t t) { return t >= 10 * kS ? 2 * kS : 0; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.steps, 1u);
  EXPECT_NEAR(static_cast<double>(clock.last_step_ns), 2.0 * kS, 1e6);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);  // and now 2 s ahead
  EXPECT_TRUE(says(clock, "stepped by +2.0 s at 2026-11-27 12:00:10 UTC")) << clock.problem;
  EXPECT_TRUE(says(clock, "now 2.0 s ahead")) << clock.problem;
}

TEST(ClockCheck, a_step_into_sync_warns_and_is_forgotten_after_a_minute) {
  ClockCheck check;
  // Counting from power-on, then locked to the host's time after 5 s.
  const std::int64_t end = Feed{.seconds = 10, .offset = [](std::int64_t t) {
                                  return t < 5 * kS ? 600 * kS - kStart : 0;
                                }}.run(check);
  ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  EXPECT_TRUE(says(clock, "stepped by +")) << clock.problem;
  EXPECT_EQ(clock.steps, 1u);
  Feed{.seconds = 70, .start = end + kMs}.run(check);
  clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::ok) << clock.problem;
  EXPECT_EQ(clock.steps, 1u);  // counted still
}

TEST(ClockCheck, a_100_ppm_drift_is_told_as_a_free_running_clock) {
  ClockCheck check;
  Feed{.seconds = 30, .offset = [](std::int64_t t) { return t / 10'000; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_NEAR(clock.drift_ppm, 100.0, 5.0);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  EXPECT_TRUE(says(clock, "drifts +100 ppm")) << clock.problem;
  EXPECT_TRUE(says(clock, "free-running")) << clock.problem;
}

TEST(ClockCheck, stamps_that_go_backwards_are_told) {
  ClockCheck check;
  // Every 500th packet carries a stamp 50 ms older than the one before it.
  Feed{.offset = [](std::int64_t t) { return t % (500 * kMs) == 0 ? -50 * kMs : 0; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  // 40 such packets in 20 s; the first is the first packet, with nothing before it.
  EXPECT_TRUE(says(clock, "went backwards (39 times")) << clock.problem;
  EXPECT_EQ(clock.steps, 0u);
}

TEST(ClockCheck, stamps_in_the_future_are_told) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t t) { return t % (500 * kMs) == 0 ? 5 * kS + 300 * kMs : 0; }}.run(check);
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  EXPECT_TRUE(says(clock, "in the future, up to 5.3 s ahead")) << clock.problem;
  ASSERT_TRUE(clock.offset_to_host_ns);
  EXPECT_LT(std::abs(*clock.offset_to_host_ns), kMs);
}

TEST(ClockCheck, a_replay_starting_over_is_neither_a_step_nor_time_going_backwards) {
  ClockCheck check;
  constexpr auto years = 3 * 365 * 86400 * kS;
  const Feed pass{.seconds = 5, .offset = [](std::int64_t) { return -years; }};
  pass.run(check);
  const ClockStatus before = judged(check);
  for (int loop = 0; loop < 3; ++loop) {
    check.restart();
    // Just after the restart the last measurement holds.
    EXPECT_EQ(judged(check).offset_to_host_ns, before.offset_to_host_ns);
    pass.run(check);
  }
  const ClockStatus clock = judged(check);
  EXPECT_EQ(clock.steps, 0u);
  EXPECT_FALSE(says(clock, "backwards")) << clock.problem;
  EXPECT_FALSE(says(clock, "stepped")) << clock.problem;
  EXPECT_TRUE(says(clock, "years behind")) << clock.problem;
  EXPECT_EQ(clock.packets_measured, 4u * 5000u);
}

TEST(ClockCheck, a_sensor_locked_but_10_s_off_a_locked_host_is_on_another_grandmaster) {
  ClockCheck check;
  Feed{.offset = [](std::int64_t) { return 10 * kS + 300 * kMs; }}.run(check);
  ClockStatus reported;
  reported.source = ClockSource::ptp;
  reported.state = ClockState::locked;
  reported.grandmaster = "00a069.fffe.0b552d";
  ClockStatus host;
  host.source = ClockSource::ptp;
  host.state = ClockState::locked;
  const ClockStatus clock = judged(check, reported, host);
  EXPECT_EQ(clock.verdict, ClockVerdict::error);
  EXPECT_TRUE(says(clock, "says its clock is locked")) << clock.problem;
  EXPECT_TRUE(says(clock, "different grandmasters or PTP domains")) << clock.problem;
  // What the sensor reported is kept.
  EXPECT_EQ(clock.grandmaster, "00a069.fffe.0b552d");
  EXPECT_EQ(clock.state, ClockState::locked);
  // The same stamps against a host that is not synchronised: just 10 s off.
  const ClockStatus unsynced = judged(check, reported, ClockStatus{});
  EXPECT_FALSE(says(unsynced, "locked")) << unsynced.problem;
  EXPECT_TRUE(says(unsynced, "10.3 s")) << unsynced.problem;
}

TEST(ClockCheck, a_sensor_that_reports_free_running_warns_before_anything_is_measured) {
  ClockCheck check;
  ClockStatus reported;
  reported.state = ClockState::free_running;
  const ClockStatus clock = judged(check, reported);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  EXPECT_TRUE(says(clock, "free-running")) << clock.problem;
}

TEST(ClockCheck, restamped_host_time_with_tiny_offsets_is_ok) {
  ClockCheck check;
  // A replay's pacing on a busy host: stamps wander 0–16 ms from the host's clock, a spread a
  // sensor would be warned for but host stamps are not.
  Feed{.offset = [](std::int64_t t) {
    const std::int64_t phase = t % (200 * kMs);
    return (phase < 100 * kMs ? phase : 200 * kMs - phase) * 16 / 100;
  }}.run(check);
  ClockStatus reported;
  reported.source = ClockSource::host;
  reported.stamps = sim::StampClock::host_arrival;
  const ClockStatus clock = judged(check, reported);
  EXPECT_EQ(clock.verdict, ClockVerdict::ok) << clock.problem;
  EXPECT_GT(clock.spread_ns, 5 * kMs);
  EXPECT_EQ(clock.source, ClockSource::host);
}

TEST(ClockCheck, hostile_stamps_never_break_the_check_and_give_finite_numbers) {
  ClockCheck check;
  constexpr auto lo = std::numeric_limits<std::int64_t>::min();
  constexpr auto hi = std::numeric_limits<std::int64_t>::max();
  const std::int64_t values[] = {lo, hi, 0, -1, 1, lo + 1, hi - 1, kStart, -kStart};
  std::uint32_t lcg = 7;
  for (int i = 0; i < 200'000; ++i) {
    lcg = lcg * 1664525u + 1013904223u;
    const std::int64_t sensor = values[lcg % 9];
    const std::int64_t arrival = (lcg >> 16) % 3 == 0 ? values[(lcg >> 8) % 9] : kStart + i * kMs;
    check.add(sensor, arrival);
    if (i % 10'000 == 0) {
      const ClockStatus clock = judged(check);
      EXPECT_TRUE(std::isfinite(clock.drift_ppm));
      EXPECT_GE(clock.spread_ns, 0);
      EXPECT_TRUE(utf8_clean(clock.problem)) << clock.problem;
      EXPECT_EQ(sim::clock_status_problem(clock), "") << clock.problem;
    }
    if (i % 77'777 == 0) check.restart();
  }
  const ClockStatus clock = judged(check);
  EXPECT_NE(clock.verdict, ClockVerdict::ok);
  EXPECT_FALSE(clock.problem.empty());
  EXPECT_LE(clock.problem.size(), ClockStatus::kMaxProblem);
}

TEST(ClockCheck, tolerances_are_per_stream) {
  // A camera's exposure and transfer: 30 ms late is its normal.
  ClockCheck strict;
  ClockCheck camera({.offset_ok_ns = 50 * kMs});
  const Feed late{.offset = [](std::int64_t) { return -30 * kMs; }};
  late.run(strict);
  late.run(camera);
  EXPECT_EQ(judged(strict).verdict, ClockVerdict::warn);
  EXPECT_TRUE(says(judged(strict), "30.3 ms behind")) << judged(strict).problem;
  EXPECT_EQ(judged(camera).verdict, ClockVerdict::ok) << judged(camera).problem;
}

}  // namespace

TEST(ClockCheck, a_warning_in_the_sensors_own_report_stands_beside_good_stamps) {
  ClockCheck check;
  Feed{}.run(check);
  ClockStatus reported;
  reported.source = ClockSource::pps_nmea;
  reported.state = ClockState::locked;
  reported.verdict = ClockVerdict::warn;
  reported.problem = "The position packets' NMEA sentence is unreadable.";
  const ClockStatus clock = judged(check, reported);
  EXPECT_EQ(clock.verdict, ClockVerdict::warn);
  EXPECT_EQ(clock.problem, reported.problem);
  reported.verdict = ClockVerdict::ok;  // an ok report with stale words says nothing
  EXPECT_EQ(judged(check, reported).verdict, ClockVerdict::ok);
}
