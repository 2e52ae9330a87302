// SPDX-License-Identifier: Apache-2.0
// The sensor's clock over Ouster's HTTP API: the /api/v1/time answer mapped into a ClockStatus
// (timestamp mode → source, port state and grandmaster → state, offsets, UTC offset, timescale),
// the answer polled from a fake sensor (fake_sensor_http.hpp, a real server on loopback) through
// every change it reports, the older /api/v1/system/time path, a sensor that does not answer;
// and sim_lidar_ouster --tai-correction auto, whose stamps are the sensor's less the announced
// 37 s. Waits have generous bounds; nothing asserts a time.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "lidar_test/fake_sensor_http.hpp"
#include "ouster_test_support.hpp"
#include "sim/apps/clock_poll.hpp"
#include "sim/ouster/route.hpp"
#include "sim/ouster/time_client.hpp"
#include "sim/ouster/time_status.hpp"
#include "sim/sim.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

using namespace std::chrono_literals;
using Json = nlohmann::json;
using lidar_test::FakeSensorHttp;
using sim::ClockSource;
using sim::ClockState;
using sim::ClockStatus;

std::optional<std::string> g_skip_reason;
const std::string live_tool = SIM_LIDAR_OUSTER;
const std::string own_id = "bc0fa7.fffe.123456";
const std::string gm_id = "001747.fffe.700038";

// An /api/v1/time answer as the manual shows one (trimmed to what matters), PTP locked.
Json time_answer(const std::string& mode = "TIME_FROM_PTP_1588") {
  return Json{
      {"sensor",
       {{"timestamp", {{"mode", mode}, {"time", 1569965466.23}}},
        {"sync_pulse_in", {{"locked", 0}, {"polarity", "ACTIVE_HIGH"}}},
        {"nmea", {{"locked", 0}, {"baud_rate", "BAUD_9600"}}}}},
      {"ptp",
       {{"port_data_set", {{"port_state", "SLAVE"}, {"port_identity", own_id + "-1"}, {"delay_mechanism", 1}}},
        {"parent_data_set", {{"grandmaster_identity", gm_id}, {"parent_port_identity", gm_id + "-1"}}},
        {"current_data_set", {{"offset_from_master", -2.0}, {"mean_path_delay", 26420.0}, {"steps_removed", 1}}},
        {"time_properties_data_set",
         {{"current_utc_offset", 37}, {"current_utc_offset_valid", 1}, {"ptp_timescale", 1}, {"time_source", 160}}},
        {"default_data_set", {{"domain_number", 0}, {"clock_identity", own_id}}},
        {"time_status_np", {{"gm_identity", gm_id}, {"gm_present", true}, {"master_offset", -2}}}}},
      {"system", {{"monotonic", 1234.5}, {"realtime", 1569965429.0}}}};
}

ClockStatus mapped(const Json& answer) {
  auto clock = sim::ouster::clock_status_from_time_json(answer.dump());
  EXPECT_TRUE(clock) << clock.error().message;
  return clock ? clock.value() : ClockStatus{};
}

sim::ouster::HttpEndpoint endpoint(std::uint16_t port, std::chrono::milliseconds timeout = 2000ms) {
  sim::ouster::HttpEndpoint e;
  e.host = "127.0.0.1";
  e.port = port;
  e.timeout = timeout;
  return e;
}

ClockStatus wait_for(const sim::apps::ClockPoll& poll, const std::function<bool(const ClockStatus&)>& wanted) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  ClockStatus latest = poll.latest();
  while (!wanted(latest) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
    latest = poll.latest();
  }
  return latest;
}

// The route the live receiver and the replay share: as ouster-sdk's pcap source, the lidar
// port to push, the IMU port to push_imu, other ports nowhere; without ports (by_port false)
// or with one port for both, the 48-byte datagrams are the IMU's.
TEST(OusterRoute, TheLidarPortGoesToPushTheImuPortToPushImuAndOtherPortsNowhere) {
  using sim::lidar::PacketKind;
  const std::vector<std::uint8_t> imu(sim::ouster::imu_packet_bytes, 0);
  const std::vector<std::uint8_t> lidar(6464, 0);
  const sim::ouster::Route route;
  EXPECT_EQ(route(7502, lidar), PacketKind::data);
  EXPECT_EQ(route(7503, imu), PacketKind::imu);
  EXPECT_EQ(route(7503, lidar), PacketKind::imu);
  EXPECT_EQ(route(9999, lidar), PacketKind::none);
  const sim::ouster::Route by_size{.by_port = false};
  EXPECT_EQ(by_size(9999, lidar), PacketKind::data);
  EXPECT_EQ(by_size(9999, imu), PacketKind::imu);
  const sim::ouster::Route one_port{.data_port = 7502, .imu_port = 7502};
  EXPECT_EQ(one_port(7502, imu), PacketKind::imu);
  EXPECT_EQ(one_port(7502, lidar), PacketKind::data);
}

}  // namespace

TEST(OusterTime, ALockedPtpSensorReportsItsOffsetDelayGrandmasterDomainAndUtcOffset) {
  const ClockStatus c = mapped(time_answer());
  EXPECT_EQ(c.source, ClockSource::ptp);
  EXPECT_EQ(c.state, ClockState::locked);
  EXPECT_EQ(c.ptp_domain, 0);
  EXPECT_EQ(c.offset_from_master_ns, -2);
  EXPECT_EQ(c.path_delay_ns, 26420);
  EXPECT_EQ(c.grandmaster, gm_id);
  EXPECT_EQ(c.utc_offset_s, 37);
  EXPECT_TRUE(c.ptp_timescale);
  EXPECT_EQ(c.stamps, sim::StampClock::sensor);
  EXPECT_EQ(c.reported_ns, 0) << "the caller says when it was read";
}

TEST(OusterTime, ThePortStateSaysTheLockAndItsOwnClockAsGrandmasterIsNotSynchronised) {
  Json a = time_answer();
  a["ptp"]["parent_data_set"]["grandmaster_identity"] = "BC0FA7.FFFE.123456";  // itself, upper case
  ClockStatus c = mapped(a);
  EXPECT_EQ(c.state, ClockState::acquiring);
  EXPECT_EQ(c.grandmaster, "");
  a = time_answer();
  a["ptp"]["port_data_set"]["port_state"] = "LISTENING";
  EXPECT_EQ(mapped(a).state, ClockState::acquiring);
  a["ptp"]["port_data_set"]["port_state"] = "MASTER";
  EXPECT_EQ(mapped(a).state, ClockState::free_running);
  a = time_answer();
  a["ptp"]["time_properties_data_set"]["current_utc_offset_valid"] = false;
  a["ptp"]["time_properties_data_set"]["ptp_timescale"] = 0;
  c = mapped(a);
  EXPECT_FALSE(c.utc_offset_s.has_value()) << "37 only when the master says it is valid";
  EXPECT_FALSE(c.ptp_timescale);
}

TEST(OusterTime, TheTimestampModeSaysTheSource) {
  ClockStatus c = mapped(time_answer("TIME_FROM_INTERNAL_OSC"));
  EXPECT_EQ(c.source, ClockSource::free_running);
  EXPECT_EQ(c.state, ClockState::free_running);
  EXPECT_FALSE(c.offset_from_master_ns.has_value()) << "PTP data of an unused PTP stack is not reported";
  Json a = time_answer("TIME_FROM_SYNC_PULSE_IN");
  c = mapped(a);
  EXPECT_EQ(c.source, ClockSource::sync_pulse);
  EXPECT_EQ(c.state, ClockState::acquiring);
  a["sensor"]["sync_pulse_in"]["locked"] = 1;
  EXPECT_EQ(mapped(a).state, ClockState::locked);
  a["sensor"]["nmea"]["locked"] = 1;
  EXPECT_EQ(mapped(a).source, ClockSource::pps_nmea);
  c = mapped(time_answer("TIME_FROM_SOMETHING_NEW"));
  EXPECT_EQ(c.source, ClockSource::unknown);
  EXPECT_EQ(c.state, ClockState::unknown);
}

TEST(OusterTime, BadAnswersAreOneSentenceAndOddFieldsAreLeftUnknown) {
  for (const char* bad : {"", "not json", "[1,2]", "{\"system\": {}}", "{\"sensor\": 1"}) {
    auto r = sim::ouster::clock_status_from_time_json(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_FALSE(r.error().message.empty());
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  }
  Json a = time_answer();
  a["ptp"]["current_data_set"]["offset_from_master"] = 1e300;    // no int64 holds it
  a["ptp"]["current_data_set"]["mean_path_delay"] = "26420";      // a string
  a["ptp"]["parent_data_set"]["grandmaster_identity"] = "\x01\x02 not an id";
  a["ptp"]["time_status_np"]["gm_identity"] = 7;
  a["ptp"]["time_properties_data_set"]["current_utc_offset"] = 1e9;
  a["ptp"]["default_data_set"]["domain_number"] = 4096;
  const ClockStatus c = mapped(a);
  EXPECT_EQ(c.source, ClockSource::ptp);
  EXPECT_EQ(c.state, ClockState::locked);
  EXPECT_FALSE(c.offset_from_master_ns.has_value());
  EXPECT_FALSE(c.path_delay_ns.has_value());
  EXPECT_EQ(c.grandmaster, "");
  EXPECT_FALSE(c.utc_offset_s.has_value());
  EXPECT_EQ(c.ptp_domain, -1);
  a["sensor"] = "nothing";  // only the PTP data left: taken as the source
  EXPECT_EQ(mapped(a).source, ClockSource::ptp);
}

TEST(OusterTime, EveryStateAndOffsetTheSensorReportsReachesThePollersLatestReading) {
  FakeSensorHttp sensor("{}");
  sensor.set_route("/api/v1/time", 200, time_answer().dump());
  sim::apps::ClockPoll poll(sim::ouster::HttpClockReader(endpoint(sensor.port())), 20ms);
  struct Step {
    Json answer;
    ClockSource source;
    ClockState state;
    std::optional<std::int64_t> offset;
    std::string grandmaster;
  };
  std::vector<Step> steps;
  steps.push_back({time_answer(), ClockSource::ptp, ClockState::locked, -2, gm_id});
  Json a = time_answer();
  a["ptp"]["port_data_set"]["port_state"] = "UNCALIBRATED";
  a["ptp"]["current_data_set"]["offset_from_master"] = 125000;
  steps.push_back({a, ClockSource::ptp, ClockState::acquiring, 125000, gm_id});
  a["ptp"]["port_data_set"]["port_state"] = "SLAVE";
  a["ptp"]["current_data_set"]["offset_from_master"] = 10'000'000'000LL;  // "locked", 10 s off
  a["ptp"]["parent_data_set"]["grandmaster_identity"] = "aabbcc.fffe.010203";
  steps.push_back({a, ClockSource::ptp, ClockState::locked, 10'000'000'000LL, "aabbcc.fffe.010203"});
  a["ptp"]["port_data_set"]["port_state"] = "FAULTY";
  steps.push_back({a, ClockSource::ptp, ClockState::free_running, 10'000'000'000LL, "aabbcc.fffe.010203"});
  Json pulse = time_answer("TIME_FROM_SYNC_PULSE_IN");
  pulse["sensor"]["sync_pulse_in"]["locked"] = 1;
  pulse["sensor"]["nmea"]["locked"] = 1;
  steps.push_back({pulse, ClockSource::pps_nmea, ClockState::locked, std::nullopt, ""});
  steps.push_back({time_answer("TIME_FROM_INTERNAL_OSC"), ClockSource::free_running, ClockState::free_running,
                   std::nullopt, ""});
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const Step& step = steps[i];
    SCOPED_TRACE("step " + std::to_string(i));
    sensor.set_route("/api/v1/time", 200, step.answer.dump());
    const ClockStatus got = wait_for(poll, [&](const ClockStatus& s) {
      return s.source == step.source && s.state == step.state && s.offset_from_master_ns == step.offset &&
             s.grandmaster == step.grandmaster;
    });
    EXPECT_EQ(got.source, step.source);
    EXPECT_EQ(got.state, step.state);
    EXPECT_EQ(got.offset_from_master_ns, step.offset);
    EXPECT_EQ(got.grandmaster, step.grandmaster);
    EXPECT_GT(got.reported_ns, 0);
  }
  bool warned = false;
  for (const auto& note : poll.take_notes()) warned = warned || note.find("locked, yet 10.0 s") != std::string::npos;
  EXPECT_TRUE(warned) << "a locked clock 10 s off is a warning";
}

TEST(OusterTime, AnOlderFirmwaresPathIsTakenAfterA404AndKept) {
  FakeSensorHttp sensor("{}");
  sensor.set_route("/api/v1/system/time", 200, time_answer().dump());
  sim::ouster::HttpClockReader read(endpoint(sensor.port()));
  for (int i = 0; i < 3; ++i) {
    const ClockStatus got = read();
    EXPECT_TRUE(got.problem.empty()) << got.problem;
    EXPECT_EQ(got.state, ClockState::locked);
  }
  EXPECT_EQ(sensor.requests_for("/api/v1/time"), 1);
  EXPECT_EQ(sensor.requests_for("/api/v1/system/time"), 3);
}

TEST(OusterTime, ASensorThatDoesNotAnswerOrDoesNotReportItsClockFailsTheReadInOneSentence) {
  FakeSensorHttp nothing("{}");  // 404 to both paths
  ClockStatus got = sim::ouster::HttpClockReader(endpoint(nothing.port()))();
  EXPECT_EQ(got.reported_ns, 0);
  EXPECT_NE(got.problem.find("to GET /api/v1/time and /api/v1/system/time; it does not report its clock"),
            std::string::npos)
      << got.problem;
  nothing.set_route("/api/v1/time", 200, "<html>not json</html>");
  got = sim::ouster::HttpClockReader(endpoint(nothing.port()))();
  EXPECT_NE(got.problem.find("is not JSON"), std::string::npos) << got.problem;
  std::uint16_t closed = 0;
  {
    FakeSensorHttp gone("{}");
    closed = gone.port();
  }
  got = sim::ouster::HttpClockReader(endpoint(closed))();
  EXPECT_EQ(got.source, ClockSource::unknown);
  EXPECT_NE(got.problem.find("refused the HTTP connection"), std::string::npos) << got.problem;
  EXPECT_EQ(got.problem.find('\n'), std::string::npos);
}

// --tai-correction auto: the sensor announces PTP timescale and a valid 37 s; the frame's stamp
// is the one the same packets get without the option, less 37 s, and the driver says so.
TEST(OusterTime, TaiCorrectionAutoPublishesTheSensorsStampsLessTheAnnouncedUtcOffset) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::string base = "OS-0-32-U1_v2.2.0_1024x10";
  const auto capture = ouster_test::load_capture(base);
  FakeSensorHttp sensor("{}");
  sensor.set_route("/api/v1/time", 200, time_answer().dump());
  const auto first_stamp = [&](bool corrected) -> std::optional<std::int64_t> {
    const std::string stream = sim::testing::unique_name("ouster_tai");
    sim::testing::StreamGuard guard(stream);
    std::vector<std::string> args{live_tool, "--calibration", ouster_test::data_path(base + ".json").string(),
                                  "--lidar-port", "0", "--imu-port", "0", "--no-imu", "--stream", stream,
                                  "--status-interval", "0", "--sensor-ip", "127.0.0.1", "--http-port",
                                  std::to_string(sensor.port()), "--clock-poll-seconds", "0.1"};
    if (corrected) {
      args.push_back("--tai-correction");
      args.push_back("auto");
    }
    sim::testing::Process driver(args);
    auto line = driver.wait_for_line("listening on");
    unsigned lidar_port = 0;
    if (!line || std::sscanf(line->c_str(), "sim_lidar_ouster: listening on %*s lidar port %u", &lidar_port) != 1) {
      ADD_FAILURE() << driver.err();
      return std::nullopt;
    }
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (corrected && driver.err().find("less 37 s") == std::string::npos &&
           std::chrono::steady_clock::now() < deadline) {
      (void)driver.wait_for_line("(no line is this)", 100ms);
    }
    auto reader = sim::testing::wait_for_stream(stream);
    if (!reader) return std::nullopt;
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(lidar_port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    for (const auto& p : capture.lidar) {
      (void)::sendto(fd, p.data(), p.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    }
    ::close(fd);
    std::vector<std::byte> buffer(reader->capacity());
    sim::FrameInfo info;
    const auto status = reader->read_next(buffer, info, 30s);
    driver.signal(SIGTERM);
    EXPECT_EQ(driver.wait(), 0) << driver.err();
    if (corrected) {
      EXPECT_NE(driver.err().find("the stamps are now the sensor's less 37 s"), std::string::npos) << driver.err();
    }
    if (status != sim::ReadStatus::new_frame) {
      ADD_FAILURE() << "no frame: " << driver.err();
      return std::nullopt;
    }
    return info.stamp_ns;
  };
  const auto raw = first_stamp(false);
  const auto corrected = first_stamp(true);
  ASSERT_TRUE(raw && corrected);
  EXPECT_EQ(*raw - *corrected, 37'000'000'000LL);
}

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::off);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
