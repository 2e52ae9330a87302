// SPDX-License-Identifier: Apache-2.0
// Stop signals end any wait of a program, and the pacer releases on the recording's schedule.
// Only lower bounds of time are asserted (a sleep never ends early); never upper bounds.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>

#include <thread>

#include "sim/apps/pacer.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"

namespace {

using sim::apps::Pacer;
using sim::apps::StopSignal;

class StopSignalTest : public ::testing::Test {
 protected:
  void SetUp() override { StopSignal::install().reset_for_test(); }
  void TearDown() override { StopSignal::install().reset_for_test(); }
};

TEST_F(StopSignalTest, SigtermIsSeenByTheFlagAndTheDescriptor) {
  StopSignal& stop = StopSignal::install();
  EXPECT_FALSE(stop.requested());
  ::raise(SIGTERM);
  EXPECT_TRUE(stop.requested());
  pollfd fd{stop.fd(), POLLIN, 0};
  EXPECT_EQ(::poll(&fd, 1, 0), 1);
}

TEST_F(StopSignalTest, SigintEndsASleepOfAnHourThatIsUnderWay) {
  StopSignal& stop = StopSignal::install();
  std::thread signaller([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ::raise(SIGINT);
  });
  // Without the stop this test would hit ctest's timeout.
  EXPECT_FALSE(stop.sleep_for(std::chrono::hours(1)));
  signaller.join();
}

TEST_F(StopSignalTest, ASleepAfterTheStopEndsAtOnce) {
  StopSignal& stop = StopSignal::install();
  stop.request();
  EXPECT_FALSE(stop.sleep_until(sim::monotonic_ns() + 3'600'000'000'000));
}

TEST_F(StopSignalTest, AnUninterruptedSleepReachesItsDeadline) {
  StopSignal& stop = StopSignal::install();
  const std::int64_t deadline = sim::monotonic_ns() + 20'000'000;
  EXPECT_TRUE(stop.sleep_until(deadline));
  EXPECT_GE(sim::monotonic_ns(), deadline);
}

TEST_F(StopSignalTest, PacerReleasesNoItemBeforeItsTimeOnTheSchedule) {
  StopSignal& stop = StopSignal::install();
  Pacer pacer(2.0);  // twice as fast: 40 ms of recording take 20 ms
  const std::int64_t recorded0 = 1'000'000'000'000;
  ASSERT_TRUE(pacer.wait(recorded0, stop));
  const std::int64_t anchor = sim::monotonic_ns();
  for (int i = 1; i <= 4; ++i) {
    ASSERT_TRUE(pacer.wait(recorded0 + i * 10'000'000, stop));
    // Released no earlier than the schedule (minus the batching window of 50 us).
    EXPECT_GE(sim::monotonic_ns() - anchor, i * 5'000'000 - 50'000 - 1'000'000) << i;
  }
}

TEST_F(StopSignalTest, AShiftedScheduleContinuesAfterTheLoopInsteadOfStartingOver) {
  StopSignal& stop = StopSignal::install();
  Pacer pacer(1.0);
  ASSERT_TRUE(pacer.wait(0, stop));
  const std::int64_t anchor = sim::monotonic_ns();
  ASSERT_TRUE(pacer.wait(10'000'000, stop));
  pacer.shift(20'000'000);  // the recording lasts 20 ms: its second pass comes after it
  ASSERT_TRUE(pacer.wait(0, stop));
  EXPECT_GE(sim::monotonic_ns() - anchor, 20'000'000 - 1'000'000);
}

TEST_F(StopSignalTest, APacerWaitingForALateItemStopsOnTheSignal) {
  StopSignal& stop = StopSignal::install();
  Pacer pacer(1.0);
  ASSERT_TRUE(pacer.wait(0, stop));
  std::thread signaller([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ::raise(SIGTERM);
  });
  EXPECT_FALSE(pacer.wait(3'600'000'000'000, stop));  // an hour later in the recording
  signaller.join();
}

TEST_F(StopSignalTest, AnUnpacedReplayNeverWaits) {
  StopSignal& stop = StopSignal::install();
  Pacer pacer(0.0);
  EXPECT_TRUE(pacer.wait(0, stop));
  EXPECT_TRUE(pacer.wait(3'600'000'000'000, stop));  // would take an hour if paced
}

}  // namespace
