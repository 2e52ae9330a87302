// SPDX-License-Identifier: Apache-2.0
// ClockPoller: readings on its own thread, a caller that never waits for a slow read, one
// change callback per change, and a destructor that does not wait out the period.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <mutex>
#include <vector>

#include "sim/timing/clock_poller.hpp"

namespace {

using namespace std::chrono_literals;
using sim::ClockSource;
using sim::ClockState;
using sim::ClockStatus;
using sim::timing::ClockPoller;

constexpr auto kBound = 60s;  // against hangs only

ClockStatus status(ClockState state, std::int64_t offset) {
  ClockStatus clock;
  clock.source = ClockSource::ptp;
  clock.state = state;
  clock.offset_from_master_ns = offset;
  clock.reported_ns = 1;
  return clock;
}

TEST(ClockPoller, ReadsAtOnceAndGivesTheLastReading) {
  std::atomic<std::int64_t> offset{5};
  ClockPoller poller([&] { return status(ClockState::locked, offset.load()); });
  ASSERT_TRUE(poller.wait_for_readings(0, kBound));
  EXPECT_EQ(poller.latest().state, ClockState::locked);
  EXPECT_EQ(poller.latest().offset_from_master_ns, 5);
  offset = 7;
  const auto before = poller.readings();
  poller.poll_now();
  ASSERT_TRUE(poller.wait_for_readings(before, kBound));
  EXPECT_EQ(poller.latest().offset_from_master_ns, 7);
}

TEST(ClockPoller, LatestNeverWaitsForAReadThatDoesNotAnswer) {
  std::promise<void> release;
  auto released = release.get_future().share();
  std::atomic<bool> reading{false};
  {
    ClockPoller poller([&] {
      reading = true;
      released.wait();  // a sensor that does not answer until the test lets it
      return status(ClockState::locked, 1);
    });
    const auto deadline = std::chrono::steady_clock::now() + kBound;
    while (!reading && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    ASSERT_TRUE(reading.load());
    // The read is blocked: the caller still gets an answer (nothing read yet), at once.
    EXPECT_EQ(poller.latest().state, ClockState::unknown);
    EXPECT_EQ(poller.latest().reported_ns, 0);
    EXPECT_EQ(poller.readings(), 0u);
    release.set_value();
    ASSERT_TRUE(poller.wait_for_readings(0, kBound));
    EXPECT_EQ(poller.latest().state, ClockState::locked);
  }  // the destructor returns although the period (1 s) has not passed: stop wakes the thread
}

TEST(ClockPoller, CallsChangedOnceForEachChangeOfSynchronisation) {
  std::mutex mutex;
  std::vector<std::pair<ClockState, ClockState>> changes;
  std::atomic<int> call{0};
  ClockPoller poller(
      [&] {
        const int n = call++;
        // locked, locked (other offset: no change), holdover, holdover, …
        return status(n < 2 ? ClockState::locked : ClockState::holdover, n);
      },
      std::chrono::hours(1),
      [&](const ClockStatus& previous, const ClockStatus& current) {
        std::lock_guard lock(mutex);
        changes.emplace_back(previous.state, current.state);
      });
  for (std::uint64_t n = 0; n < 4; ++n) {
    ASSERT_TRUE(poller.wait_for_readings(n, kBound));
    poller.poll_now();
  }
  ASSERT_TRUE(poller.wait_for_readings(4, kBound));
  std::lock_guard lock(mutex);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0], std::make_pair(ClockState::unknown, ClockState::locked));
  EXPECT_EQ(changes[1], std::make_pair(ClockState::locked, ClockState::holdover));
}

TEST(ClockPoller, SameSynchronisationIgnoresOffsetsButNotTheGrandmaster) {
  auto a = status(ClockState::locked, 1);
  auto b = status(ClockState::locked, 2);
  EXPECT_TRUE(sim::timing::same_synchronisation(a, b));
  b.grandmaster = "00a069.fffe.0b552d";
  EXPECT_FALSE(sim::timing::same_synchronisation(a, b));
}

}  // namespace
