// SPDX-License-Identifier: Apache-2.0
// ClockReporter against a real SIM stream: which clock a frame's stamp is in is known before the
// clock is judged (the sensor's, the recording's, or host time), so every frame carries its
// FrameInfo::stamp_clock from the first one; the verdict waits for the first judgement.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/reader.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/writer.hpp"
#include "sim_test/streams.hpp"

namespace {

using sim::ClockSource;
using sim::ClockStatus;
using sim::ClockVerdict;
using sim::StampClock;
using sim::timing::ClockBase;
using sim::timing::ClockReporter;
using sim::timing::ClockSources;

constexpr std::int64_t kStart = 1'790'000'000'000'000'000;  // made-up host time of the first packet

sim::Writer make_writer(const std::string& name) {
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = 64;
  auto writer = sim::Writer::create(spec);
  EXPECT_TRUE(writer) << writer.error().message;
  return std::move(*writer);
}

// Publishes one frame as a LiDAR stream does (its stamp chosen by the reporter) and returns what a
// reader gets with it.
sim::FrameInfo publish_first_frame(sim::Writer& writer, sim::Reader& reader, ClockReporter& clock) {
  const std::int64_t stamp = clock.frame_stamp(writer, kStart, kStart + 500'000);
  const std::vector<std::byte> frame(16, std::byte{1});
  EXPECT_EQ(writer.write(std::span<const std::byte>(frame), stamp), sim::WriteStatus::ok);
  std::vector<std::byte> buffer(reader.capacity());
  sim::FrameInfo info;
  EXPECT_EQ(reader.read(buffer, info), sim::ReadStatus::new_frame);
  return info;
}

ClockStatus record_of(sim::Reader& reader) {
  auto clock = reader.clock();
  EXPECT_TRUE(clock) << clock.error().message;
  if (!clock || !*clock) {
    ADD_FAILURE() << "the stream has no clock record";
    return {};
  }
  return **clock;
}

struct FirstFrame {
  const char* what;
  ClockBase base;
  sim::timing::StampFallback fallback;
  StampClock stamps;
  ClockSource source;
};

TEST(ClockReporter, the_first_frame_carries_its_stamp_clock_before_the_clock_is_judged) {
  using sim::timing::StampFallback;
  for (const FirstFrame& c : {
           FirstFrame{"live", ClockBase::sensor, StampFallback::off, StampClock::sensor, ClockSource::unknown},
           FirstFrame{"replayed", ClockBase::replayed, StampFallback::off, StampClock::sensor, ClockSource::replayed},
           FirstFrame{"restamped", ClockBase::restamped, StampFallback::off, StampClock::host_arrival, ClockSource::host},
           FirstFrame{"stamp fallback host", ClockBase::sensor, StampFallback::host, StampClock::host_arrival,
                      ClockSource::unknown},
       }) {
    SCOPED_TRACE(c.what);
    sim::testing::StreamGuard stream(sim::testing::unique_name("reporter_first"));
    sim::Writer writer = make_writer(stream.name);
    auto reader = sim::Reader::open(stream.name);
    ASSERT_TRUE(reader) << reader.error().message;
    ClockReporter clock;
    clock.set_base(c.base);
    ClockSources sources;
    sources.stamp_fallback = c.fallback;
    sources.log = [](const std::string&) {};
    clock.set_sources(sources);
    // A few packets, well within the first quarter second: no judgement yet.
    for (std::int64_t i = 0; i < 10; ++i) {
      clock.add(kStart + i * 1'000'000, kStart + i * 1'000'000 + 400'000);
      EXPECT_FALSE(clock.tick(writer, kStart + i * 1'000'000 + 400'000));
    }
    const sim::FrameInfo first = publish_first_frame(writer, *reader, clock);
    EXPECT_EQ(first.stamp_clock, c.stamps);
    const ClockStatus record = record_of(*reader);
    EXPECT_EQ(record.verdict, ClockVerdict::unknown);
    EXPECT_EQ(record.source, c.source);
    EXPECT_EQ(record.stamps, c.stamps);
    EXPECT_EQ(record.problem.rfind(ClockReporter::kNotJudged, 0), 0u) << record.problem;
  }
}

TEST(ClockReporter, the_first_judgement_replaces_the_unjudged_record) {
  sim::testing::StreamGuard stream(sim::testing::unique_name("reporter_judged"));
  sim::Writer writer = make_writer(stream.name);
  auto reader = sim::Reader::open(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  ClockReporter clock;
  clock.set_base(ClockBase::replayed);
  (void)publish_first_frame(writer, *reader, clock);
  EXPECT_EQ(record_of(*reader).verdict, ClockVerdict::unknown);
  std::int64_t t = kStart;
  for (; t < kStart + ClockReporter::kFirstNs + 10'000'000; t += 1'000'000) {
    clock.add(t, t + 400'000);
    (void)clock.tick(writer, t + 400'000);
  }
  const ClockStatus judged = record_of(*reader);
  EXPECT_EQ(judged.verdict, ClockVerdict::ok) << judged.problem;
  EXPECT_EQ(judged.source, ClockSource::replayed);
  EXPECT_EQ(judged.stamps, StampClock::sensor);
  EXPECT_GT(judged.packets_measured, 0u);
}

TEST(ClockReporter, a_driver_that_commits_frames_itself_starts_the_record_with_what_its_source_says) {
  // A camera stamping frames at their arrival says so through its reported clock.
  sim::testing::StreamGuard stream(sim::testing::unique_name("reporter_camera"));
  sim::Writer writer = make_writer(stream.name);
  auto reader = sim::Reader::open(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  ClockReporter clock;
  ClockSources sources;
  sources.reported = [] {
    ClockStatus reported;
    reported.source = ClockSource::host;
    reported.stamps = StampClock::host_arrival;
    return reported;
  };
  clock.set_sources(sources);
  clock.start(writer);
  const std::vector<std::byte> frame(16, std::byte{1});
  ASSERT_EQ(writer.write(std::span<const std::byte>(frame), kStart), sim::WriteStatus::ok);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.stamp_clock, StampClock::host_arrival);
  EXPECT_EQ(record_of(*reader).source, ClockSource::host);
}

TEST(ClockReporter, a_stream_created_anew_gets_the_last_judgement_before_its_first_frame) {
  ClockReporter clock;
  clock.set_base(ClockBase::replayed);
  {
    sim::testing::StreamGuard stream(sim::testing::unique_name("reporter_old"));
    sim::Writer writer = make_writer(stream.name);
    for (std::int64_t t = kStart; t < kStart + ClockReporter::kFirstNs + 10'000'000; t += 1'000'000) {
      clock.add(t, t + 400'000);
      (void)clock.tick(writer, t + 400'000);
    }
    ASSERT_TRUE(clock.last());
  }
  sim::testing::StreamGuard stream(sim::testing::unique_name("reporter_new"));
  sim::Writer writer = make_writer(stream.name);
  auto reader = sim::Reader::open(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  clock.new_stream();
  const sim::FrameInfo first = publish_first_frame(writer, *reader, clock);
  EXPECT_EQ(first.stamp_clock, StampClock::sensor);
  EXPECT_EQ(record_of(*reader), *clock.last());
}

}  // namespace
