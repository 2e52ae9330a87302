// SPDX-License-Identifier: Apache-2.0
// The sensor's clock over PTC, against the fake sensor of fake_ptc_sensor.hpp (a real TCP server
// on loopback): what it reports — every state, offset, profile, domain, grandmaster, GPS lock —
// reaches the ClockStatus the poller returns after each change; a sensor without a PTC server,
// a silent one, a reply cut short, a "locked" clock 10 s off and a grandmaster that keeps
// changing are a sentence or a warning, never a crash, a hang or a stopped stream. Waits have
// generous bounds; nothing asserts a time.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "fake_ptc_sensor.hpp"
#include "sim/apps/clock_poll.hpp"
#include "sim/hesai/ptc_clock.hpp"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"

namespace {

using namespace std::chrono_literals;
using hesai_test::Behaviour;
using hesai_test::FakeClock;
using hesai_test::FakeSensor;
using sim::ClockSource;
using sim::ClockState;
using sim::ClockStatus;

const std::string live_tool = SIM_LIDAR_HESAI;

sim::hesai::PtcEndpoint endpoint(std::uint16_t port, std::chrono::milliseconds timeout = 2000ms) {
  sim::hesai::PtcEndpoint e;
  e.host = "127.0.0.1";
  e.port = port;
  e.timeout = timeout;
  return e;
}

// Waits (60 s at most) until the poller's latest reading satisfies `wanted`; that reading.
ClockStatus wait_for(const sim::apps::ClockPoll& poll, const std::function<bool(const ClockStatus&)>& wanted) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  ClockStatus latest = poll.latest();
  while (!wanted(latest) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
    latest = poll.latest();
  }
  return latest;
}

struct Want {
  ClockSource source;
  ClockState state;
  std::int32_t domain;
  std::optional<std::int64_t> offset;
  std::string grandmaster;
};

}  // namespace

TEST(PtcClock, EveryStateAndOffsetTheSensorReportsReachesThePollersLatestReading) {
  FakeSensor sensor(Behaviour::serve);
  sim::apps::ClockPoll poll(sim::hesai::PtcClockReader(endpoint(sensor.port()), std::nullopt), 20ms);
  const std::string gm = "001747.fffe.700038";
  struct Step {
    FakeClock clock;
    Want expected;
  };
  std::vector<Step> steps;
  FakeClock c;  // PTP 1588 domain 0, locked, 120 ns from its master
  c.master_offset_ns = 120;
  steps.push_back({c, {ClockSource::ptp, ClockState::locked, 0, 120, gm}});
  c.ptp_status = 1;  // tracking, further off
  c.master_offset_ns = -5'000;
  c.port_state = 8;  // UNCALIBRATED
  steps.push_back({c, {ClockSource::ptp, ClockState::acquiring, 0, -5'000, gm}});
  c.ptp_status = 3;  // frozen: holdover
  c.master_offset_ns = 40'000;
  steps.push_back({c, {ClockSource::ptp, ClockState::holdover, 0, 40'000, gm}});
  c.ptp_status = 0;  // free run
  steps.push_back({c, {ClockSource::ptp, ClockState::free_running, 0, 40'000, gm}});
  c.ptp_status = 2;  // gPTP (802.1AS automotive) in domain 24, another grandmaster
  c.profile = 3;
  c.domain = 24;
  c.master_offset_ns = 7;
  c.grandmaster = {0xaa, 0xbb, 0xcc, 0xff, 0xfe, 0x01, 0x02, 0x03};
  steps.push_back({c, {ClockSource::gptp, ClockState::locked, 24, 7, "aabbcc.fffe.010203"}});
  FakeClock gps;  // PTP off: the GPS inputs
  gps.ptp_enabled = false;
  gps.pps_locked = true;
  steps.push_back({gps, {ClockSource::pps_nmea, ClockState::acquiring, -1, std::nullopt, ""}});
  gps.gprmc_locked = true;
  steps.push_back({gps, {ClockSource::pps_nmea, ClockState::locked, -1, std::nullopt, ""}});
  FakeClock qt;  // a QT128's status layout, an older firmware without 0x26
  qt.qt_layout = true;
  qt.answers_ptp_config = false;
  qt.ptp_status = 1;
  qt.master_offset_ns = -900;
  steps.push_back({qt, {ClockSource::ptp, ClockState::acquiring, -1, -900, gm}});

  for (std::size_t i = 0; i < steps.size(); ++i) {
    const Step& step = steps[i];
    SCOPED_TRACE("step " + std::to_string(i));
    sensor.set_clock(step.clock);
    const Want& e = step.expected;
    const ClockStatus got = wait_for(poll, [&](const ClockStatus& s) {
      return s.source == e.source && s.state == e.state && s.ptp_domain == e.domain &&
             s.offset_from_master_ns == e.offset && s.grandmaster == e.grandmaster;
    });
    EXPECT_EQ(got.source, e.source);
    EXPECT_EQ(got.state, e.state);
    EXPECT_EQ(got.ptp_domain, e.domain);
    EXPECT_EQ(got.offset_from_master_ns, e.offset);
    EXPECT_EQ(got.grandmaster, e.grandmaster);
    EXPECT_GT(got.reported_ns, 0);
    EXPECT_TRUE(got.problem.empty()) << got.problem;
    if (e.source == ClockSource::ptp && step.clock.answers_ptp_config) {
      ASSERT_TRUE(got.utc_offset_s.has_value());
      EXPECT_EQ(*got.utc_offset_s, 37);
      EXPECT_TRUE(got.ptp_timescale);
    }
  }
}

TEST(PtcClock, APeerDelayAndAUtcOffsetNotMarkedValidAreReportedAsTheSensorMeansThem) {
  FakeSensor sensor(Behaviour::serve);
  FakeClock c;
  c.profile = 1;  // 802.1AS: peer delay
  c.delay_mechanism = 2;
  c.peer_path_delay_ns = 812;
  c.time_flags = 0;  // UTC offset not valid, UTC timescale
  sensor.set_clock(c);
  const ClockStatus got = sim::hesai::PtcClockReader(endpoint(sensor.port()), sim::hesai::Model::pandar_xt32)();
  ASSERT_TRUE(got.problem.empty()) << got.problem;
  EXPECT_EQ(got.source, ClockSource::gptp);
  EXPECT_EQ(got.path_delay_ns, 812);
  EXPECT_FALSE(got.utc_offset_s.has_value());
  EXPECT_FALSE(got.ptp_timescale);
  EXPECT_EQ(sensor.clock_requests(), 6);  // 0x26, 0x09, 0x06 × 4
}

TEST(PtcClock, ASensorWithoutAPtcServerOrASilentOneFailsTheReadInOneSentence) {
  {
    const ClockStatus got = sim::hesai::PtcClockReader(endpoint(hesai_test::closed_port()), std::nullopt)();
    EXPECT_EQ(got.reported_ns, 0);
    EXPECT_EQ(got.source, ClockSource::unknown);
    EXPECT_EQ(got.state, ClockState::unknown);
    EXPECT_NE(got.problem.find("refused the PTC connection"), std::string::npos) << got.problem;
    EXPECT_EQ(got.problem.find('\n'), std::string::npos);
  }
  {
    FakeSensor sensor(Behaviour::silent);
    const ClockStatus got = sim::hesai::PtcClockReader(endpoint(sensor.port(), 300ms), std::nullopt)();
    EXPECT_EQ(got.reported_ns, 0);
    EXPECT_NE(got.problem.find("did not answer within 0.3 s"), std::string::npos) << got.problem;
  }
  {
    // A poller over a silent sensor: readings keep coming (each ends by its deadline), and the
    // poller stops when asked.
    FakeSensor sensor(Behaviour::silent);
    sim::apps::ClockPoll poll(sim::hesai::PtcClockReader(endpoint(sensor.port(), 100ms), std::nullopt), 10ms);
    ASSERT_TRUE(poll.poller().wait_for_readings(2, 60s));
    const auto notes = poll.take_notes();
    ASSERT_EQ(notes.size(), 1u) << "one warning while it lasts";
    EXPECT_NE(notes[0].find("warning: cannot read the sensor's clock: sensor 127.0.0.1:"), std::string::npos)
        << notes[0];
  }
}

TEST(PtcClock, AReplyCutShortAnAbsurdOffsetAndAFlappingGrandmasterAreWarningsNotFailures) {
  FakeSensor sensor(Behaviour::serve);
  FakeClock c;
  c.cut_to = 5;  // every answer announces its size and stops after 5 bytes
  sensor.set_clock(c);
  const ClockStatus cut = sim::hesai::PtcClockReader(endpoint(sensor.port()), std::nullopt)();
  EXPECT_EQ(cut.reported_ns, 0);
  EXPECT_NE(cut.problem.find("closed the PTC connection after 5 of the"), std::string::npos) << cut.problem;

  // "Locked", and as far from its master as an int64 goes: stored as reported, and a warning.
  c.cut_to = SIZE_MAX;
  c.master_offset_ns = std::numeric_limits<std::int64_t>::min();
  sensor.set_clock(c);
  sim::apps::ClockPoll poll(sim::hesai::PtcClockReader(endpoint(sensor.port()), std::nullopt), 20ms);
  const ClockStatus far = wait_for(poll, [](const ClockStatus& s) { return s.reported_ns != 0; });
  EXPECT_EQ(far.state, ClockState::locked);
  EXPECT_EQ(far.offset_from_master_ns, std::numeric_limits<std::int64_t>::min());
  ASSERT_TRUE(poll.poller().wait_for_readings(1, 60s));
  const auto notes = poll.take_notes();
  bool warned = false;
  for (const auto& note : notes) warned = warned || note.find("says its clock is locked, yet") != std::string::npos;
  EXPECT_TRUE(warned) << (notes.empty() ? "no notes" : notes.back());
}

TEST(PtcClock, TheDriverSaysWhatTheSensorsClockReportsAndWarnsOfALockedClockTenSecondsOff) {
  FakeSensor sensor(Behaviour::serve);
  FakeClock c;
  c.master_offset_ns = 10'000'000'000;  // "locked", 10 s off
  c.qt_layout = true;                   // a QT128's status answer
  sensor.set_clock(c);
  const std::string stream = "/test_hesai_clock_" + std::to_string(::getpid());
  sim::testing::Process driver({live_tool, "--calibration", std::string(SIM_HESAI_TEST_DATA) + "/pandarqt128.calibration.csv",
                                "--model", "PandarQT128", "--port", "0", "--bind", "127.0.0.1", "--stream", stream,
                                "--status-interval", "0", "--sensor-ip", "127.0.0.1", "--ptc-port",
                                std::to_string(sensor.port()), "--clock-poll-seconds", "0.2"});
  ASSERT_TRUE(driver.wait_for_line("listening on")) << driver.err();
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (driver.err().find("10.0 s from its master") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline) {
    (void)driver.wait_for_line("(no line is this)", 100ms);
  }
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(), 0) << driver.err();
  EXPECT_NE(driver.err().find("the sensor's clock: PTP, locked, grandmaster 001747.fffe.700038"), std::string::npos)
      << driver.err();
  EXPECT_NE(driver.err().find("warning: the sensor says its clock is locked, yet 10.0 s from its master"),
            std::string::npos)
      << driver.err();
  (void)sim::destroy(stream, true);
}
