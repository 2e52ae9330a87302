// SPDX-License-Identifier: Apache-2.0
// ClockNotes: what a person is told about a sensor's successive clock reports, on made-up
// reports at made-up times (no clock is read): a change of state, a "locked" clock far from its
// master, a grandmaster that changes every second, a clock that cannot be read — each said
// once, and again at most once a minute while it lasts; and the report of a failed read.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "sim/timing/clock_notes.hpp"

namespace {

using sim::ClockSource;
using sim::ClockState;
using sim::ClockStatus;
constexpr std::int64_t kSecond = 1'000'000'000;

ClockStatus report(ClockState state, std::int64_t offset_ns, const std::string& grandmaster) {
  ClockStatus c;
  c.source = ClockSource::ptp;
  c.state = state;
  c.offset_from_master_ns = offset_ns;
  c.grandmaster = grandmaster;
  c.reported_ns = 1;
  return c;
}

bool has(const std::vector<std::string>& notes, const std::string& words) {
  for (const auto& note : notes) {
    if (note.find(words) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST(ClockNotes, AChangeOfStateIsSaidOnceAndASteadyClockNotAgain) {
  sim::timing::ClockNotes notes;
  auto said = notes.update(report(ClockState::acquiring, 5000, "001747.fffe.700038"), 1 * kSecond);
  EXPECT_TRUE(has(said, "the sensor's clock: PTP, acquiring, grandmaster 001747.fffe.700038")) << said.size();
  EXPECT_TRUE(notes.update(report(ClockState::acquiring, 4000, "001747.fffe.700038"), 2 * kSecond).empty());
  said = notes.update(report(ClockState::locked, 20, "001747.fffe.700038"), 3 * kSecond);
  EXPECT_TRUE(has(said, "PTP, locked"));
  EXPECT_EQ(said.size(), 1u);
}

TEST(ClockNotes, ALockedClockFarFromItsMasterIsAWarningRepeatedAtMostOnceAMinute) {
  sim::timing::ClockNotes notes;
  const auto far = report(ClockState::locked, 10 * kSecond, "001747.fffe.700038");
  EXPECT_TRUE(has(notes.update(far, 1 * kSecond), "warning: the sensor says its clock is locked, yet 10.0 s"));
  for (int s = 2; s < 60; ++s) EXPECT_TRUE(notes.update(far, s * kSecond).empty()) << s;
  EXPECT_TRUE(has(notes.update(far, 62 * kSecond), "locked, yet 10.0 s"));
  // The most negative offset there is: a size, not an overflow.
  const auto absurd = report(ClockState::locked, std::numeric_limits<std::int64_t>::min(), "001747.fffe.700038");
  sim::timing::ClockNotes fresh;
  EXPECT_TRUE(has(fresh.update(absurd, kSecond), "locked, yet 2562047.8 h"));
  // Acquiring far off is what acquiring means: no warning.
  sim::timing::ClockNotes acquiring;
  EXPECT_FALSE(has(acquiring.update(report(ClockState::acquiring, 10 * kSecond, ""), kSecond), "warning"));
}

TEST(ClockNotes, AGrandmasterThatChangesEverySecondIsAWarningNotEachChange) {
  sim::timing::ClockNotes notes;
  const std::string a = "001747.fffe.700038", b = "aabbcc.fffe.010203";
  int warnings = 0;
  for (int s = 0; s < 120; ++s) {
    const auto said = notes.update(report(ClockState::locked, 10, s % 2 == 0 ? a : b), (s + 1) * kSecond);
    if (has(said, "warning: the sensor's grandmaster changed")) ++warnings;
    EXPECT_FALSE(has(said, "locked, yet"));
  }
  EXPECT_EQ(warnings, 2) << "once, then once more a minute later";
}

TEST(ClockNotes, AClockThatCannotBeReadIsSaidOnceAndItsReturnToo) {
  sim::timing::ClockNotes notes;
  const ClockStatus failed = sim::timing::clock_read_failed("sensor 10.0.0.1:9347 refused the PTC connection");
  EXPECT_EQ(failed.reported_ns, 0);
  EXPECT_EQ(failed.source, ClockSource::unknown);
  EXPECT_TRUE(has(notes.update(failed, kSecond), "warning: cannot read the sensor's clock: sensor 10.0.0.1:9347"));
  EXPECT_TRUE(notes.update(failed, 2 * kSecond).empty());
  EXPECT_TRUE(has(notes.update(report(ClockState::locked, 0, ""), 3 * kSecond), "can be read again"));
}

TEST(ClockNotes, AFailedReadsSentenceIsCutToTheRecordsLimitAtACharacterBoundary) {
  std::string long_text(ClockStatus::kMaxProblem - 1, 'a');
  long_text += "µµµ";  // a two-byte character across the limit
  const ClockStatus c = sim::timing::clock_read_failed(long_text);
  EXPECT_LE(c.problem.size(), ClockStatus::kMaxProblem);
  EXPECT_EQ(c.problem, std::string(ClockStatus::kMaxProblem - 1, 'a'));
}
