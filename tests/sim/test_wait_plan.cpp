// SPDX-License-Identifier: Apache-2.0
// The adaptive wait's decisions against a simulated clock: every time here is a number, nothing
// sleeps and nothing is timed.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>

#include "../../sim/wake_plan.hpp"

using sim::detail::SpinLeases;
using sim::detail::StreamTiming;
using sim::detail::WakePlanner;
using sim::detail::WakeStep;
using Action = sim::detail::WakeStep::Action;

namespace {
constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kUs = 1'000;

// A 100 Hz stream whose newest frame was published at t = 1 s.
StreamTiming steady(std::int64_t jitter_ns = 5 * kUs) {
  return {.latest_publish_ns = 1000 * kMs, .period_ns = 10 * kMs, .jitter_ns = jitter_ns,
          .frames_this_writer = 100};
}
}  // namespace

TEST(WakePlanner, SleepsUntilShortlyBeforeTheNextExpectedPublish) {
  const WakePlanner planner;
  const auto& p = planner.params();
  const WakeStep step = planner.next(1001 * kMs, steady());
  EXPECT_EQ(step.action, Action::sleep);
  const std::int64_t expected = 1010 * kMs;
  EXPECT_LT(step.until, expected);
  // The wake-up margin plus a guard of at least min_guard_ns before the publish, no more.
  EXPECT_EQ(step.until, expected - p.wake_margin_ns - p.min_guard_ns);
}

TEST(WakePlanner, SpinsAroundTheExpectedPublishForABoundedShareOfThePeriod) {
  const WakePlanner planner;
  const WakeStep sleep = planner.next(1001 * kMs, steady());
  const WakeStep spin = planner.next(sleep.until, steady());
  ASSERT_EQ(spin.action, Action::spin);
  EXPECT_GT(spin.until, 1010 * kMs);  // covers the expected publish itself
  EXPECT_LE(spin.until - sleep.until, steady().period_ns / planner.params().max_spin_share_inverse);
}

TEST(WakePlanner, WidensTheGuardBandWithTheObservedJitter) {
  const WakePlanner planner;
  const WakeStep calm = planner.next(1001 * kMs, steady(5 * kUs));
  const WakeStep jittery = planner.next(1001 * kMs, steady(40 * kUs));
  EXPECT_LT(jittery.until, calm.until);  // starts spinning earlier
  EXPECT_EQ(calm.until - jittery.until, 3 * 40 * kUs - planner.params().min_guard_ns);
}

TEST(WakePlanner, SpendsTheRestOfItsSpinBudgetAfterTheExpectedPublish) {
  // A writer's timer wakes late more often than early: a calm stream's window starts just
  // before the expected publish and runs on for the whole budget.
  const WakePlanner planner;
  const WakeStep sleep = planner.next(1001 * kMs, steady());
  const WakeStep spin = planner.next(sleep.until, steady());
  ASSERT_EQ(spin.action, Action::spin);
  EXPECT_EQ(spin.until - sleep.until, steady().period_ns / planner.params().max_spin_share_inverse);
}

TEST(WakePlanner, KeepsAsMuchOfAShortBudgetAfterTheExpectedPublishAsBefore) {
  // Jitter of 100 µs asks for a 300 µs guard on each side; the 400 µs budget (4 % of 10 ms)
  // cannot hold both plus the wake margin, so the guard shrinks and the window stays centred.
  const WakePlanner planner;
  const auto& p = planner.params();
  const StreamTiming t = steady(100 * kUs);
  const WakeStep sleep = planner.next(1001 * kMs, t);
  const WakeStep spin = planner.next(sleep.until, t);
  ASSERT_EQ(spin.action, Action::spin);
  const std::int64_t expected = 1010 * kMs;
  const std::int64_t budget = t.period_ns / p.max_spin_share_inverse;
  EXPECT_EQ(spin.until - sleep.until, budget);
  EXPECT_EQ(spin.until - expected, expected - p.wake_margin_ns - sleep.until);
}

TEST(WakePlanner, StartsEarlierWhenItsSleepsHaveBeenWakingLate) {
  const WakePlanner planner;
  const WakeStep usual = planner.next(1001 * kMs, steady());
  const WakeStep late = planner.next(1001 * kMs, steady(), 250 * kUs);
  EXPECT_EQ(usual.until - late.until, 250 * kUs - planner.params().wake_margin_ns);
  // Smaller lateness than the margin changes nothing.
  EXPECT_EQ(planner.next(1001 * kMs, steady(), 10 * kUs).until, usual.until);
}

TEST(WakeLateness, FollowsTheObservedLatenessSmoothly) {
  sim::detail::WakeLateness late;
  for (int i = 0; i < 100; ++i) late.add(200 * kUs);
  EXPECT_NEAR(static_cast<double>(late.ns()), 200.0 * kUs, 10.0 * kUs);
  late.add(-5);  // a clock read before the deadline counts as on time, never negative
  EXPECT_GE(late.ns(), 0);
}

TEST(WakeLateness, IsNotDraggedAwayByARareWakeUpMillisecondsLate) {
  // A VM's vCPU descheduled now and then: the typical lateness is what the window must follow.
  sim::detail::WakeLateness late;
  for (int i = 0; i < 200; ++i) late.add((i % 50 == 49 ? 3000 : 150) * kUs);
  EXPECT_NEAR(static_cast<double>(late.ns()), 150.0 * kUs, 30.0 * kUs);
}

TEST(WakePlanner, NeverSpinsLongerThanItsShareEvenWithLargeJitter) {
  const WakePlanner planner;
  const StreamTiming t = steady(2 * kMs);  // 20 % of the period: still below the aperiodic cut
  const WakeStep sleep = planner.next(1000 * kMs + kUs, t);
  ASSERT_EQ(sleep.action, Action::sleep);
  const WakeStep spin = planner.next(sleep.until, t);
  ASSERT_EQ(spin.action, Action::spin);
  EXPECT_LE(spin.until - sleep.until, t.period_ns / planner.params().max_spin_share_inverse);
}

TEST(WakePlanner, BlocksWithoutSpinningOnAnAperiodicStream) {
  const WakePlanner planner;
  EXPECT_EQ(planner.next(1001 * kMs, steady(3 * kMs)).action, Action::block);  // jitter > period/4
  StreamTiming unknown = steady();
  unknown.period_ns = 0;
  EXPECT_EQ(planner.next(1001 * kMs, unknown).action, Action::block);
}

TEST(WakePlanner, BlocksUntilTheWritersPeriodIsEstablished) {
  const WakePlanner planner;
  StreamTiming young = steady();
  young.frames_this_writer = 2;
  EXPECT_EQ(planner.next(1001 * kMs, young).action, Action::block);
  StreamTiming empty = steady();
  empty.latest_publish_ns = 0;
  EXPECT_EQ(planner.next(1001 * kMs, empty).action, Action::block);
}

TEST(WakePlanner, BlocksOnASilentStream) {
  const WakePlanner planner;
  // A writer that paused for seconds: no spinning at all, whatever the phase.
  for (std::int64_t now = 1041 * kMs; now < 4000 * kMs; now += 7 * kMs + 13 * kUs) {
    ASSERT_EQ(planner.next(now, steady()).action, Action::block) << now;
  }
}

TEST(WakePlanner, AfterAMissedFrameWaitsForTheFollowingOne) {
  const WakePlanner planner;
  // The frame due at 1010 ms did not come; at 1012 ms the reader sleeps until the 1020 ms window.
  const WakeStep step = planner.next(1012 * kMs, steady());
  ASSERT_EQ(step.action, Action::sleep);
  EXPECT_GT(step.until, 1012 * kMs);
  EXPECT_LT(step.until, 1020 * kMs);
  EXPECT_EQ(planner.next(step.until, steady()).action, Action::spin);
}

TEST(WakePlanner, ALateFrameEndsTheSpinAndTheReaderSleepsOnTheFutex) {
  const WakePlanner planner;
  const WakeStep spin = planner.next(1010 * kMs - 50 * kUs, steady());
  ASSERT_EQ(spin.action, Action::spin);
  const WakeStep after = planner.next(spin.until, steady());
  EXPECT_EQ(after.action, Action::sleep);  // futex: a publish wakes it, no more spinning
  EXPECT_GT(after.until, 1019 * kMs);
}

TEST(WakePlanner, SpinShareOverAWholeSimulatedRunStaysWithinItsBound) {
  // Drive the planner like a reader would: each step ends when its time comes or a frame
  // arrives; frames arrive every period with a fixed pattern of deviations within the jitter.
  const WakePlanner planner;
  const std::int64_t period = 10 * kMs;
  const std::int64_t deviations[] = {0, 15 * kUs, -12 * kUs, 7 * kUs, -20 * kUs, 3 * kUs};
  StreamTiming t{.latest_publish_ns = 1000 * kMs, .period_ns = period, .jitter_ns = 10 * kUs,
                 .frames_this_writer = 50};
  std::int64_t now = t.latest_publish_ns + 100 * kUs;
  std::int64_t spun = 0;
  int caught_spinning = 0;
  const int frames = 600;
  for (int i = 1; i <= frames; ++i) {
    const std::int64_t arrival = 1000 * kMs + i * period + deviations[i % 6];
    while (now < arrival) {
      const WakeStep step = planner.next(now, t);
      const std::int64_t end = step.action == Action::block ? arrival : std::min(step.until, arrival);
      if (step.action == Action::spin) {
        spun += end - now;
        if (end == arrival) ++caught_spinning;
      }
      now = std::max(end, now + 1);
    }
    t.latest_publish_ns = arrival;
    ++t.frames_this_writer;
    now = arrival + 30 * kUs;  // the reader handles the frame and waits again
  }
  EXPECT_EQ(caught_spinning, frames);  // every frame within the jitter arrived during a spin
  EXPECT_LE(spun, static_cast<std::int64_t>(frames) * period / planner.params().max_spin_share_inverse);
}

TEST(SpinLeases, NeverGrantMoreThanTheLimit) {
  std::atomic<std::int64_t> leases[4] = {0, 0, 0, 0};
  EXPECT_EQ(SpinLeases::acquire(leases, 2, 100, 200), 0);
  EXPECT_EQ(SpinLeases::acquire(leases, 2, 100, 200), 1);
  EXPECT_EQ(SpinLeases::acquire(leases, 2, 100, 200), -1);
  SpinLeases::release(leases, 0, 200);
  EXPECT_EQ(SpinLeases::acquire(leases, 2, 100, 300), 0);
}

TEST(SpinLeases, ALeaseOfASpinnerThatDiedExpiresByItself) {
  std::atomic<std::int64_t> leases[1] = {0};
  ASSERT_EQ(SpinLeases::acquire(leases, 1, 100, 500), 0);  // never released: the spinner died
  EXPECT_EQ(SpinLeases::acquire(leases, 1, 499, 900), -1);
  EXPECT_EQ(SpinLeases::acquire(leases, 1, 500, 900), 0);
  SpinLeases::release(leases, 0, 500);  // the dead one's late release leaves the new lease alone
  EXPECT_EQ(leases[0].load(), 900);
}
