// SPDX-License-Identifier: Apache-2.0
// StampSwitch, the rule of --stamp-fallback host, on made-up frames (a frame every 100 ms, the
// sensor's stamps some offset from their arrival) and made-up verdicts: host arrival time while
// the verdict is error or not judged yet, the sensor's otherwise, each switch told once, and no
// switch ever taking the stamps backwards.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>

#include "sim/timing/stamp_switch.hpp"

namespace {

using sim::ClockVerdict;
using sim::timing::StampEvent;
using sim::timing::StampFallback;
using sim::timing::StampSwitch;

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kS = 1'000'000'000;
constexpr std::int64_t kStart = 1'800'000'000 * kS;  // 2027: a plausible host time

// Frame `i` of a stream whose sensor clock is `offset` from the host, arriving 2 ms after its
// sensor stamp would say on a synchronised clock.
struct Frames {
  std::int64_t offset = 0;
  std::int64_t sensor(int i) const { return kStart + i * 100 * kMs + offset; }
  static std::int64_t host(int i) { return kStart + i * 100 * kMs + 2 * kMs; }
};

TEST(StampSwitch, off_publishes_the_sensors_stamps_whatever_the_verdict) {
  StampSwitch stamps;
  EXPECT_FALSE(stamps.enabled());
  const Frames frames{37 * kS};
  for (int i = 0; i < 3; ++i) {
    const auto choice = stamps.choose(frames.sensor(i), Frames::host(i), ClockVerdict::error);
    EXPECT_EQ(choice.stamp_ns, frames.sensor(i));
    EXPECT_EQ(choice.event, StampEvent::none);
  }
  sim::ClockStatus clock;
  clock.verdict = ClockVerdict::error;
  clock.problem = "The sensor's clock is 37 s ahead.";
  clock.stamps = sim::StampClock::sensor;
  stamps.describe(clock);
  EXPECT_EQ(clock.stamps, sim::StampClock::sensor);
  EXPECT_EQ(clock.problem, "The sensor's clock is 37 s ahead.");
}

TEST(StampSwitch, a_clock_in_error_gets_host_arrival_stamps_from_the_first_frame_and_says_why_once) {
  StampSwitch stamps(StampFallback::host);
  const Frames frames{37 * kS};
  // Not judged yet: untrusted, so the first frames are never 37 s ahead.
  auto choice = stamps.choose(frames.sensor(0), Frames::host(0), std::nullopt);
  EXPECT_EQ(choice.stamp_ns, Frames::host(0));
  EXPECT_EQ(choice.event, StampEvent::none);
  EXPECT_TRUE(stamps.on_host());
  // The first verdict, error: still host time, now told why; then nothing more to tell.
  choice = stamps.choose(frames.sensor(1), Frames::host(1), ClockVerdict::error);
  EXPECT_EQ(choice.stamp_ns, Frames::host(1));
  EXPECT_EQ(choice.event, StampEvent::to_host);
  sim::ClockStatus clock;
  clock.verdict = ClockVerdict::error;
  clock.problem = "The sensor's clock is 37 s ahead of this host.";
  clock.stamps = sim::StampClock::sensor;
  const std::string line = stamps.explain(choice, &clock);
  EXPECT_NE(line.find("host arrival time"), std::string::npos) << line;
  EXPECT_NE(line.find("37 s ahead"), std::string::npos) << line;
  for (int i = 2; i < 20; ++i) {
    choice = stamps.choose(frames.sensor(i), Frames::host(i), ClockVerdict::error);
    EXPECT_EQ(choice.stamp_ns, Frames::host(i));
    EXPECT_EQ(choice.event, StampEvent::none);
  }
  // The record keeps the sentence about the sensor's clock and adds what the frames are in.
  stamps.describe(clock);
  EXPECT_EQ(clock.stamps, sim::StampClock::host_arrival);
  EXPECT_EQ(clock.problem.rfind("The sensor's clock is 37 s ahead of this host.", 0), 0u) << clock.problem;
  EXPECT_NE(clock.problem.find("stamped with host arrival time"), std::string::npos) << clock.problem;
}

TEST(StampSwitch, a_healthy_clock_gets_the_sensors_stamps_from_its_first_verdict) {
  StampSwitch stamps(StampFallback::host);
  const Frames frames{0};
  EXPECT_EQ(stamps.choose(frames.sensor(0), Frames::host(0), std::nullopt).stamp_ns, Frames::host(0));
  // Its sensor stamp (100 ms later, less 2 ms) is past the host stamp before it: no hold.
  auto choice = stamps.choose(frames.sensor(1), Frames::host(1), ClockVerdict::ok);
  EXPECT_EQ(choice.event, StampEvent::to_sensor);
  EXPECT_EQ(choice.stamp_ns, frames.sensor(1));
  EXPECT_FALSE(stamps.on_host());
  choice = stamps.choose(frames.sensor(2), Frames::host(2), ClockVerdict::warn);  // usable: stays
  EXPECT_EQ(choice.event, StampEvent::none);
  EXPECT_EQ(choice.stamp_ns, frames.sensor(2));
}

TEST(StampSwitch, a_clock_that_recovers_goes_back_to_its_own_stamps) {
  StampSwitch stamps(StampFallback::host);
  const Frames frames{-3600 * kS};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(stamps.choose(frames.sensor(i), Frames::host(i), ClockVerdict::error).stamp_ns, Frames::host(i));
  const Frames recovered{1 * kMs};
  const auto choice = stamps.choose(recovered.sensor(5), Frames::host(5), ClockVerdict::ok);
  EXPECT_EQ(choice.event, StampEvent::to_sensor);
  EXPECT_EQ(choice.stamp_ns, recovered.sensor(5));
  sim::ClockStatus clock;
  clock.verdict = ClockVerdict::ok;
  clock.stamps = sim::StampClock::sensor_tai_corrected;
  stamps.describe(clock);
  EXPECT_EQ(clock.stamps, sim::StampClock::sensor_tai_corrected);  // as the judgement said
  EXPECT_NE(stamps.explain(choice, &clock).find("sensor's clock"), std::string::npos);
}

TEST(StampSwitch, a_switch_back_waits_for_the_sensors_stamp_to_pass_the_last_one) {
  StampSwitch stamps(StampFallback::host);
  const Frames broken{-3600 * kS};
  for (int i = 0; i < 5; ++i) (void)stamps.choose(broken.sensor(i), Frames::host(i), ClockVerdict::error);
  // Recovering: 120 ms behind, so its stamp lies 22 ms before the last host stamp published; a frame
  // later 10 ms behind, past it.
  const Frames slewing{-120 * kMs};
  auto choice = stamps.choose(slewing.sensor(5), Frames::host(5), ClockVerdict::warn);
  EXPECT_EQ(choice.event, StampEvent::held);
  EXPECT_EQ(choice.stamp_ns, Frames::host(5));
  const std::string line = stamps.explain(choice, nullptr);
  EXPECT_NE(line.find("warning"), std::string::npos) << line;
  EXPECT_NE(line.find("back by 22"), std::string::npos) << line;
  const Frames recovered{-10 * kMs};
  choice = stamps.choose(recovered.sensor(6), Frames::host(6), ClockVerdict::warn);
  EXPECT_EQ(choice.event, StampEvent::to_sensor);
  EXPECT_EQ(choice.stamp_ns, recovered.sensor(6));
  EXPECT_GT(choice.stamp_ns, Frames::host(5));
  sim::ClockStatus clock;
  clock.verdict = ClockVerdict::warn;
  EXPECT_EQ(stamps.explain(choice, &clock).find("went back"), std::string::npos);
}

TEST(StampSwitch, a_clock_far_ahead_switches_after_a_second_and_says_how_far_the_stamps_went_back) {
  StampSwitch stamps(StampFallback::host);
  const Frames frames{0};
  EXPECT_EQ(stamps.choose(frames.sensor(0), Frames::host(0), ClockVerdict::ok).event, StampEvent::to_sensor);
  // The sensor's clock steps 2 s ahead: frames went out 2 s ahead before the verdict said
  // error. Host time never passes the sensor's stamps, so the switch waits a second, then goes.
  const Frames ahead{2 * kS};
  int warnings = 0;
  int switched_at = -1;
  std::int64_t last = 0;
  for (int i = 1; i < 40 && switched_at < 0; ++i) {
    const auto verdict = i < 5 ? ClockVerdict::ok : ClockVerdict::error;
    const auto choice = stamps.choose(ahead.sensor(i), Frames::host(i), verdict);
    if (choice.event == StampEvent::held) ++warnings;
    if (choice.event == StampEvent::to_host) {
      switched_at = i;
      EXPECT_EQ(choice.stamp_ns, Frames::host(i));
      EXPECT_LT(choice.stamp_ns, last);
      const std::string line = stamps.explain(choice, nullptr);
      EXPECT_NE(line.find("went back by 1.9 s"), std::string::npos) << line;
    } else {
      EXPECT_GT(choice.stamp_ns, last) << "frame " << i;
    }
    last = choice.stamp_ns;
  }
  EXPECT_EQ(warnings, 1);
  EXPECT_EQ(switched_at, 15);  // held at frame 5, a second of host time later
  EXPECT_TRUE(stamps.on_host());
}

TEST(StampSwitch, a_long_problem_sentence_is_cut_to_fit_the_record) {
  StampSwitch stamps(StampFallback::host);
  (void)stamps.choose(kStart, kStart, ClockVerdict::error);
  sim::ClockStatus clock;
  clock.verdict = ClockVerdict::error;
  for (int i = 0; i < 50; ++i) clock.problem += "word ";
  stamps.describe(clock);
  EXPECT_LE(clock.problem.size(), sim::ClockStatus::kMaxProblem);
  EXPECT_NE(clock.problem.find("word... Meanwhile"), std::string::npos) << clock.problem;
  EXPECT_EQ(sim::clock_status_problem(clock), "");
  EXPECT_NE(clock.problem.find("(--stamp-fallback host)."), std::string::npos) << clock.problem;
}

}  // namespace
