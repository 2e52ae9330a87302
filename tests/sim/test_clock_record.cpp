// SPDX-License-Identifier: Apache-2.0
// The stream's clock record (issue 30): what a writer sets reaches every reader typed and whole,
// a change is seen through FrameInfo::clock_generation without reopening, each frame says which
// clock its stamp is in, bad records are refused with one sentence, and a damaged record in a
// region is reported while frames keep flowing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "../../sim/region.hpp"
#include "sim/sim.h"
#include "sim/sim.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using sim::detail::ClockBlock;
using sim::detail::ClockRecord;
using sim::detail::RegionHeader;
using test::StreamGuard;
using test::unique_name;

namespace {

ClockStatus ptp_clock() {
  ClockStatus c;
  c.source = ClockSource::ptp;
  c.state = ClockState::locked;
  c.ptp_domain = 0;
  c.offset_from_master_ns = -42;
  c.path_delay_ns = 1'250;
  c.grandmaster = "00a069.fffe.0b552d";
  c.utc_offset_s = 37;
  c.ptp_timescale = true;
  c.tai_correction_ns = 37'000'000'000;
  c.reported_ns = 1'790'000'000'000'000'000;
  c.offset_to_host_ns = 12'000;
  c.spread_ns = 3'000;
  c.drift_ppm = 0.25;
  c.steps = 1;
  c.last_step_ns = -37'000'000'000;
  c.packets_measured = 36'000;
  c.measured_ns = 1'790'000'000'500'000'000;
  c.verdict = ClockVerdict::ok;
  c.stamps = StampClock::sensor_tai_corrected;
  return c;
}

ClockStatus free_running_clock() {
  ClockStatus c;
  c.source = ClockSource::free_running;
  c.state = ClockState::free_running;
  c.offset_to_host_ns = -80'000'000'000'000'000;  // 2.5 years behind
  c.drift_ppm = 31.5;
  c.verdict = ClockVerdict::error;
  c.problem = "the sensor's clock is 2.5 years behind the host; synchronise it (PTP) or restamp";
  c.stamps = StampClock::sensor;
  return c;
}

Writer make_writer(const std::string& name) {
  StreamSpec spec;
  spec.name = name;
  spec.capacity = 256;
  auto w = Writer::create(spec);
  EXPECT_TRUE(w) << w.error().message;
  return std::move(*w);
}

void publish(Writer& w) {
  const std::vector<std::byte> frame(64, std::byte{7});
  ASSERT_EQ(w.write(std::span<const std::byte>(frame), 1), WriteStatus::ok);
}

FrameInfo next_frame(Reader& r) {
  std::vector<std::byte> buf(r.capacity());
  FrameInfo info;
  EXPECT_EQ(r.read(buf, info), ReadStatus::new_frame);
  return info;
}

template <typename T>
void poke_clock(const std::string& name, std::size_t offset_in_block, T value) {
  const int fd = open(("/dev/shm/sim." + name.substr(1)).c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  const off_t at = static_cast<off_t>(detail::kHeaderOffset + offsetof(RegionHeader, clock) + offset_in_block);
  ASSERT_EQ(pwrite(fd, &value, sizeof value, at), static_cast<ssize_t>(sizeof value));
  close(fd);
}
template <typename T>
void poke_record(const std::string& name, std::size_t offset_in_record, T value) {
  poke_clock(name, offsetof(ClockBlock, record) + offset_in_record, value);
}

}  // namespace

TEST(ClockRecordValues, DurationsReadAsPeopleSayThem) {
  EXPECT_EQ(human_duration(0), "0 ns");
  EXPECT_EQ(human_duration(12'000), "12 µs");
  EXPECT_EQ(human_duration(-37'000'000'000), "-37.0 s");
  EXPECT_EQ(human_duration(3'600'000'000'000), "1.0 h");
  EXPECT_EQ(human_duration(80'000'000'000'000'000), "2.5 years");
  EXPECT_EQ(human_duration(std::numeric_limits<std::int64_t>::min()), "-292.3 years");
}

TEST(ClockRecordValues, SummaryNamesSourceStateOffsetsAndVerdict) {
  const std::string line = summary(ptp_clock());
  EXPECT_EQ(line.rfind("ptp locked, domain 0, grandmaster 00a069.fffe.0b552d", 0), 0u) << line;
  EXPECT_NE(line.find("offset to host +12 µs ±3 µs"), std::string::npos) << line;
  EXPECT_NE(line.find("TAI corrected by 37.0 s"), std::string::npos) << line;
  EXPECT_EQ(line.substr(line.size() - 4), ": ok") << line;
  ClockStatus unmeasured;
  EXPECT_EQ(summary(unmeasured), "unknown unknown, offset to host not measured yet: unknown");
  const std::string bad = summary(free_running_clock());
  EXPECT_NE(bad.find(": error: the sensor's clock is 2.5 years behind"), std::string::npos) << bad;
}

TEST(ClockRecordStream, ClockSetByTheWriterReachesReadersTypedAndWhole) {
  StreamGuard g{unique_name("clock_set")};
  Writer w = make_writer(g.name);
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r) << r.error().message;
  auto none = r->clock();
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_FALSE(none->has_value()) << "a stream whose writer said nothing has no clock record";

  ASSERT_TRUE(w.set_clock(ptp_clock()));
  auto clock = r->clock();
  ASSERT_TRUE(clock) << clock.error().message;
  ASSERT_TRUE(clock->has_value());
  EXPECT_EQ(**clock, ptp_clock());
  auto status = inspect(g.name);
  ASSERT_TRUE(status) << status.error().message;
  ASSERT_TRUE(status->clock.has_value());
  EXPECT_EQ(*status->clock, ptp_clock());
  EXPECT_NE(status->clock_generation, 0u);
}

TEST(ClockRecordStream, AChangeIsSeenByTheNextFrameWithoutReopening) {
  StreamGuard g{unique_name("clock_change")};
  Writer w = make_writer(g.name);
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r);
  publish(w);
  const FrameInfo before = next_frame(*r);
  EXPECT_EQ(before.clock_generation, 0u);
  EXPECT_EQ(before.stamp_clock, StampClock::unknown);

  ASSERT_TRUE(w.set_clock(ptp_clock()));
  publish(w);
  const FrameInfo first = next_frame(*r);
  EXPECT_NE(first.clock_generation, 0u);
  EXPECT_EQ(first.stamp_clock, StampClock::sensor_tai_corrected);

  ASSERT_TRUE(w.set_clock(free_running_clock()));
  publish(w);
  const FrameInfo second = next_frame(*r);
  EXPECT_GT(second.clock_generation, first.clock_generation);
  EXPECT_EQ(second.stamp_clock, StampClock::sensor) << "each frame carries the clock in force when published";
  EXPECT_EQ(second.sensor_generation, 0u) << "a clock change is not a new sensor description";
  auto clock = r->clock();
  ASSERT_TRUE(clock && clock->has_value());
  EXPECT_EQ(**clock, free_running_clock());
}

TEST(ClockRecordStream, BadRecordIsRefusedWithOneSentence) {
  StreamGuard g{unique_name("clock_bad")};
  Writer w = make_writer(g.name);
  struct Case {
    const char* words;
    void (*spoil)(ClockStatus&);
  };
  const Case cases[] = {
      {"drift is not a finite", [](ClockStatus& c) { c.drift_ppm = std::nan(""); }},
      {"problem sentence must be at most 255", [](ClockStatus& c) { c.problem.assign(300, 'x'); }},
      {"printable", [](ClockStatus& c) { c.grandmaster = "00a069\n"; }},
      {"clock source 99 is unknown", [](ClockStatus& c) { c.source = static_cast<ClockSource>(99); }},
      {"PTP domain 300", [](ClockStatus& c) { c.ptp_domain = 300; }},
  };
  for (const Case& bad : cases) {
    SCOPED_TRACE(bad.words);
    ClockStatus c = ptp_clock();
    bad.spoil(c);
    auto set = w.set_clock(c);
    ASSERT_FALSE(set);
    EXPECT_NE(set.error().message.find(bad.words), std::string::npos) << set.error().message;
    EXPECT_NE(set.error().message.find(g.name), std::string::npos) << set.error().message;
  }
}

TEST(ClockRecordStream, ANewWriterStartsWithoutTheOldWritersClock) {
  StreamGuard g{unique_name("clock_new_writer")};
  std::uint64_t old_generation = 0;
  {
    Writer w = make_writer(g.name);
    ASSERT_TRUE(w.set_clock(free_running_clock()));
    auto status = inspect(g.name);
    ASSERT_TRUE(status);
    old_generation = status->clock_generation;
  }
  Writer w = make_writer(g.name);
  auto status = inspect(g.name);
  ASSERT_TRUE(status);
  EXPECT_FALSE(status->clock.has_value()) << "the dead writer's verdict would describe another clock";
  ASSERT_TRUE(w.set_clock(ptp_clock()));
  status = inspect(g.name);
  ASSERT_TRUE(status);
  EXPECT_GT(status->clock_generation, old_generation) << "a generation is never reused";
}

// Each way a record in a region can be damaged: one sentence, frames keep flowing.
TEST(ClockRecordDamage, DamagedRecordIsReportedAndFramesKeepFlowing) {
  struct Damage {
    const char* words;
    void (*apply)(const std::string& name);
  };
  const Damage damages[] = {
      {"clock state 9 is unknown",
       [](const std::string& n) { poke_record<std::uint32_t>(n, offsetof(ClockRecord, state), 9); }},
      {"flags this library does not know",
       [](const std::string& n) { poke_record<std::uint32_t>(n, offsetof(ClockRecord, flags), 0x100); }},
      {"drift is not a finite",
       [](const std::string& n) {
         poke_record<double>(n, offsetof(ClockRecord, drift_ppm), std::numeric_limits<double>::infinity());
       }},
      {"grandmaster is not a NUL-terminated",
       [](const std::string& n) {
         for (std::size_t i = 0; i < detail::kGrandmasterField; ++i) {
           poke_record<char>(n, offsetof(ClockRecord, grandmaster) + i, 'g');
         }
       }},
      {"bytes outside its fields",  // a value behind a clear has_ bit
       [](const std::string& n) { poke_record<std::int64_t>(n, offsetof(ClockRecord, path_delay_ns), 5); }},
      {"stopped in the middle",
       [](const std::string& n) {
         poke_clock<std::uint64_t>(n, 0, 4 * 9 + detail::kSensorPresent + detail::kSensorWriting);
       }},
  };
  for (const Damage& damage : damages) {
    SCOPED_TRACE(damage.words);
    StreamGuard g{unique_name("clock_damaged")};
    Writer w = make_writer(g.name);
    ClockStatus without_delay = ptp_clock();
    without_delay.path_delay_ns.reset();
    ASSERT_TRUE(w.set_clock(without_delay));
    auto r = Reader::open(g.name);
    ASSERT_TRUE(r);
    damage.apply(g.name);
    auto clock = r->clock();
    ASSERT_FALSE(clock) << "a damaged record was accepted";
    const std::string& message = clock.error().message;
    // Damaged, or (a writer stuck mid-change) not readable now: one sentence either way.
    EXPECT_EQ(message.rfind("the stream's clock record ", 0), 0u) << message;
    EXPECT_NE(message.find(damage.words), std::string::npos) << message;
    publish(w);
    next_frame(*r);  // frames still flow
    auto status = inspect(g.name);
    ASSERT_TRUE(status);
    EXPECT_FALSE(status->clock.has_value());
    EXPECT_EQ(status->clock_problem, message);
    ASSERT_TRUE(w.set_clock(ptp_clock()));  // the writer's next record repairs it
    auto repaired = r->clock();
    ASSERT_TRUE(repaired) << repaired.error().message;
    EXPECT_TRUE(repaired->has_value());
  }
}

// A reader copying the record while the writer keeps changing it (once a second in a driver,
// without pause here) gets one of the records whole, never a mix.
TEST(ClockRecordConcurrency, ConcurrentUpdatesNeverTearTheRecord) {
  StreamGuard g{unique_name("clock_race")};
  const ClockStatus a = ptp_clock();
  const ClockStatus b = free_running_clock();
  Writer w = make_writer(g.name);
  ASSERT_TRUE(w.set_clock(a));
  auto r = Reader::open(g.name);
  ASSERT_TRUE(r);
  std::atomic<bool> stop{false};
  std::thread updater([&] {
    for (int i = 0; !stop.load(std::memory_order_relaxed); ++i) {
      ASSERT_TRUE(w.set_clock(i % 2 == 0 ? b : a));
      std::this_thread::yield();
    }
  });
  int torn = 0;
  for (int i = 0; i < 5000; ++i) {
    auto clock = r->clock();
    ASSERT_TRUE(clock) << clock.error().message;
    ASSERT_TRUE(clock->has_value());
    if (**clock != a && **clock != b) ++torn;
  }
  stop = true;
  updater.join();
  EXPECT_EQ(torn, 0);
}

TEST(ClockRecordCApi, CProgramsSetAndReadTheSameRecord) {
  StreamGuard g{unique_name("clock_c")};
  sim_writer* w = SIM_writerInit(g.name.c_str(), 256);
  ASSERT_NE(w, nullptr) << SIM_lastError();
  sim_clock_status in{};
  in.source = SIM_CLOCK_SOURCE_PTP;
  in.state = SIM_CLOCK_STATE_ACQUIRING;
  in.ptp_domain = 24;
  in.has_offset_to_host = 1;
  in.offset_to_host_ns = 37'000'000'123;
  in.verdict = SIM_CLOCK_ERROR;
  std::strcpy(in.problem, "37 s ahead: TAI");
  std::strcpy(in.grandmaster, "001122.fffe.334455");
  in.stamps = SIM_STAMP_SENSOR;
  ASSERT_EQ(SIM_writerSetClock(w, &in), 0) << SIM_lastError();
  sim_reader* r = SIM_readerInit(g.name.c_str(), 256);
  ASSERT_NE(r, nullptr) << SIM_lastError();
  sim_clock_status out{};
  ASSERT_EQ(SIM_readerClock(r, &out), 1) << SIM_lastError();
  EXPECT_EQ(out.state, SIM_CLOCK_STATE_ACQUIRING);
  EXPECT_EQ(out.ptp_domain, 24);
  EXPECT_EQ(out.has_offset_to_host, 1);
  EXPECT_EQ(out.offset_to_host_ns, 37'000'000'123);
  EXPECT_EQ(out.has_offset_from_master, 0);
  EXPECT_STREQ(out.problem, "37 s ahead: TAI");
  EXPECT_STREQ(out.grandmaster, "001122.fffe.334455");
  char frame[8] = {};
  ASSERT_EQ(SIM_writeData(w, frame, sizeof frame), 0) << SIM_lastError();
  sim_frame_info info{};
  ASSERT_EQ(SIM_readData(r, frame, sizeof frame, &info), 8) << SIM_lastError();
  EXPECT_NE(SIM_readerClockGeneration(r), 0u);
  EXPECT_EQ(SIM_readerStampClock(r), SIM_STAMP_SENSOR);
  in.verdict = 7;
  EXPECT_EQ(SIM_writerSetClock(w, &in), SIM_EINVAL);
  EXPECT_NE(std::string(SIM_lastError()).find("verdict 7 is unknown"), std::string::npos) << SIM_lastError();
  SIM_readerClose(r);
  SIM_writerClose(w);
}

// ---- pairing by stamps only where the clocks agree (sim/pairing.hpp) ----

namespace {
ClockStatus measured(std::int64_t offset_to_host_ns, ClockVerdict verdict = ClockVerdict::ok) {
  ClockStatus c;
  c.source = ClockSource::ptp;
  c.state = ClockState::locked;
  c.offset_to_host_ns = offset_to_host_ns;
  c.verdict = verdict;
  return c;
}
}  // namespace

TEST(ClockPairing, ClocksThatAgreeWithinTheToleranceMayBePaired) {
  EXPECT_EQ(pairing_problem("/cam", measured(2'000'000), "/lidar", measured(-3'000'000), 10'000'000), "");
  EXPECT_EQ(pairing_problem("/cam", ClockStatus{}, "/lidar", ClockStatus{}, 1), "")
      << "nothing known is no reason to refuse";
}

TEST(ClockPairing, RefusalsNameBothStreamsAndTheReason) {
  const std::string apart = pairing_problem("/cam", measured(0), "/lidar", measured(37'000'000'000), 20'000'000);
  EXPECT_NE(apart.find("the clocks of /cam and /lidar disagree by 37.0 s"), std::string::npos) << apart;
  EXPECT_NE(apart.find("tolerance of 20.0 ms"), std::string::npos) << apart;

  ClockStatus broken = measured(0, ClockVerdict::error);
  broken.problem = "stepped by +2.0 s";
  const std::string error = pairing_problem("/cam", measured(0), "/lidar", broken, 20'000'000);
  EXPECT_NE(error.find("/lidar's clock is in error (stepped by +2.0 s)"), std::string::npos) << error;
  EXPECT_NE(error.find("paired with /cam's"), std::string::npos) << error;

  ClockStatus a = measured(0), b = measured(0);
  a.grandmaster = "001122.fffe.334455";
  b.grandmaster = "001122.fffe.667788";
  EXPECT_NE(pairing_problem("/a", a, "/b", b, 1'000'000).find("different PTP grandmasters"), std::string::npos);
  b.grandmaster = a.grandmaster;
  a.ptp_domain = 0;
  b.ptp_domain = 24;
  EXPECT_NE(pairing_problem("/a", a, "/b", b, 1'000'000).find("different PTP domains (0, 24)"), std::string::npos);

  const std::string extreme = pairing_problem("/a", measured(INT64_MIN), "/b", measured(INT64_MAX), 1);
  EXPECT_NE(extreme.find("disagree by"), std::string::npos) << "no overflow at the limits: " << extreme;
}

TEST(ClockPairing, ThePairerRefusesWhileClocksDisagreeUnlessToldTo) {
  ApproximatePairer<int, int> pairer(std::chrono::milliseconds(20));
  pairer.set_clocks("/cam", measured(0), "/lidar", measured(37'000'000'000));
  pairer.add_first(1'000, 1);
  pairer.add_second(2'000, 2);
  EXPECT_FALSE(pairer.take()) << "stamps 1 µs apart, clocks 37 s apart: the pair would be wrong";
  EXPECT_NE(pairer.refusal().find("disagree by 37.0 s"), std::string::npos) << pairer.refusal();

  pairer.ignore_clocks(true);
  EXPECT_TRUE(pairer.refusal().empty());
  auto forced = pairer.take();
  ASSERT_TRUE(forced);
  EXPECT_EQ(forced->first, 1);

  pairer.ignore_clocks(false);
  pairer.set_clocks("/cam", measured(0), "/lidar", measured(1'000'000));
  pairer.add_first(5'000, 3);
  pairer.add_second(6'000, 4);
  EXPECT_TRUE(pairer.take()) << "clocks 1 ms apart are within 20 ms";
}
