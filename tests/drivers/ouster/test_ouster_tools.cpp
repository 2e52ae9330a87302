// SPDX-License-Identifier: Apache-2.0
// The Ouster programs as a user runs them, as real processes in a private network namespace:
// sim_replay_pcap detects an Ouster capture (and says in one sentence that it needs the
// metadata), reassembles a fragmented one, names metadata that does not fit; sim_lidar_ouster
// fetches the metadata from a fake sensor's HTTP API on loopback, caches it, falls back to the
// cache when the sensor does not answer, and publishes the frame and IMU samples it receives.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "lidar_test/fake_sensor_http.hpp"
#include "lidar_test/capture_frames.hpp"
#include "ouster_test_support.hpp"
#include "sim/sim.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using sim::testing::Process;
using sim::testing::StreamGuard;
using sim::testing::unique_name;

std::optional<std::string> g_skip_reason;
const std::string replay_tool = SIM_REPLAY_PCAP;
const std::string live_tool = SIM_LIDAR_OUSTER;
const std::string dual = "OS-0-32-U1_v2.2.0_1024x10";
const std::string legacy = "OS-1-32-G_v2.1.1_1024x10";

std::string data(const std::string& name) { return ouster_test::data_path(name).string(); }

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("sim_ouster_tools_" + std::to_string(::getpid()) + "_" +
                                               std::to_string(counter()++));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
  static std::atomic<int>& counter() {
    static std::atomic<int> c{0};
    return c;
  }
};

bool one_sentence(const std::string& err) {
  // "<tool>: <sentence>.\n" and nothing else.
  return !err.empty() && err.find('\n') == err.size() - 1;
}

TEST(OusterReplay, TheDualReturnCapturePublishesItsFrameAndImuSamples) {
  const std::string stream = unique_name("ouster_replay");
  StreamGuard guard(stream);
  guard.names.push_back(stream + ".imu");
  const auto r = sim::testing::run({replay_tool, data(dual + ".pcap"), "--calibration", data(dual + ".json"),
                                    "--stream", stream, "--max-rate", "--summary", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("frames=1 packets=64 lost=0 malformed=0 imu=10 points=65536"), std::string::npos) << r.out;
}

// Which clock the replayed stamps are: this host's with --restamp, otherwise the sensor's as
// recorded, whose synchronisation an Ouster capture does not show.
TEST(OusterReplay, TheStreamSaysWhichClockItsStampsAreWithAndWithoutRestamp) {
  struct Case {
    bool restamp;
    sim::TimeBase time_base;
    std::string time_sync;
  };
  const std::vector<Case> cases = {
      {true, sim::TimeBase::host, "replayed, restamped to this host's clock"},
      {false, sim::TimeBase::unknown,
       "replayed with the recorded stamps (the sensor's clock; the recording does not say whether it was "
       "synchronised)"},
  };
  for (const Case& expected : cases) {
    const std::string stream = unique_name("ouster_clock");
    StreamGuard guard(stream);
    guard.names.push_back(stream + ".imu");
    std::vector<std::string> argv{replay_tool, data(dual + ".pcap"), "--calibration", data(dual + ".json"),
                                  "--stream",  stream,             "--max-rate",    "-q"};
    if (expected.restamp) argv.push_back("--restamp");
    const auto r = sim::testing::run(argv);
    ASSERT_EQ(r.code, 0) << r.err;
    auto reader = sim::Reader::open(stream);
    ASSERT_TRUE(reader) << reader.error().message;
    auto described = reader->sensor_info();
    ASSERT_TRUE(described && *described) << "restamp " << expected.restamp;
    EXPECT_EQ((*described)->time_base, expected.time_base) << "restamp " << expected.restamp;
    EXPECT_EQ((*described)->time_sync, expected.time_sync) << "restamp " << expected.restamp;
  }
}

// The IMU's samples are in the IMU's frame: its stream says so, mounted on the points' frame by
// the metadata's imu_to_sensor_transform (the OS-0-32's: identity rotation, (6.253, −11.775,
// 7.645) mm), so ROS 2 and Foxglove get the transform ouster-ros publishes as os_sensor → os_imu.
TEST(OusterReplay, TheImuStreamIsDescribedInItsOwnFrameMountedByTheMetadatasImuTransform) {
  const std::string stream = unique_name("ouster_imu_frame");
  StreamGuard guard(stream);
  guard.names.push_back(stream + ".imu");
  const auto r = sim::testing::run({replay_tool, data(dual + ".pcap"), "--calibration", data(dual + ".json"),
                                    "--stream", stream, "--frame-id", "os_top", "--max-rate", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto points = sim::Reader::open(stream);
  auto imu = sim::Reader::open(stream + ".imu");
  ASSERT_TRUE(points && imu);
  auto points_info = points->sensor_info();
  auto imu_info = imu->sensor_info();
  ASSERT_TRUE(points_info && *points_info && imu_info && *imu_info);
  const sim::SensorInfo& p = **points_info;
  const sim::SensorInfo& i = **imu_info;
  EXPECT_EQ(p.frame_id, "os_top");
  EXPECT_EQ(i.frame_id, "os_top_imu");
  EXPECT_EQ(i.parent_frame, "os_top");
  ASSERT_TRUE(i.mounting);
  EXPECT_NEAR(i.mounting->translation[0], 0.006253, 1e-9);
  EXPECT_NEAR(i.mounting->translation[1], -0.011775, 1e-9);
  EXPECT_NEAR(i.mounting->translation[2], 0.007645, 1e-9);
  EXPECT_NEAR(i.mounting->rotation[3], 1.0, 1e-12);  // identity: w = 1
  EXPECT_EQ(i.point_time, sim::PointTime::none);
  EXPECT_EQ(i.identity.serial, p.identity.serial);
  EXPECT_EQ(i.time_base, p.time_base);
}

// A rotated IMU (a half turn about z here, as the lidar of the same unit is mounted) gives its
// rotation as a unit quaternion: (0, 0, ±1, 0).
TEST(OusterReplay, ARotatedImuTransformBecomesItsMountingsQuaternion) {
  TempDir dir;
  std::string json = ouster_test::read_text(data(dual + ".json"));
  const std::string identity = "\"imu_to_sensor_transform\": [1, 0, 0, 6.253, 0, 1, 0, -11.775, 0, 0, 1, 7.645, 0, 0, 0, 1]";
  const std::size_t at = json.find(identity);
  ASSERT_NE(at, std::string::npos);
  json.replace(at, identity.size(), "\"imu_to_sensor_transform\": [-1, 0, 0, 10, 0, -1, 0, 20, 0, 0, 1, 30, 0, 0, 0, 1]");
  const fs::path metadata = dir.path / "rotated_imu.json";
  std::ofstream(metadata) << json;
  const std::string stream = unique_name("ouster_imu_rotated");
  StreamGuard guard(stream);
  guard.names.push_back(stream + ".imu");
  const auto r = sim::testing::run({replay_tool, data(dual + ".pcap"), "--calibration", metadata.string(), "--stream",
                                    stream, "--max-rate", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto imu = sim::Reader::open(stream + ".imu");
  ASSERT_TRUE(imu);
  auto described = imu->sensor_info();
  ASSERT_TRUE(described && *described && (*described)->mounting);
  const sim::Mounting& m = *(*described)->mounting;
  EXPECT_NEAR(m.translation[0], 0.010, 1e-12);
  EXPECT_NEAR(m.translation[1], 0.020, 1e-12);
  EXPECT_NEAR(m.translation[2], 0.030, 1e-12);
  EXPECT_NEAR(m.rotation[0], 0.0, 1e-12);
  EXPECT_NEAR(m.rotation[1], 0.0, 1e-12);
  EXPECT_NEAR(std::abs(m.rotation[2]), 1.0, 1e-12);
  EXPECT_NEAR(m.rotation[3], 0.0, 1e-12);
}

TEST(OusterReplay, ACaptureWithoutItsMetadataIsRecognisedAndTheUserToldToGiveIt) {
  const auto r = sim::testing::run({replay_tool, data(legacy + ".pcap"), "--stream", unique_name("ouster_nometa")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("holds Ouster lidar packets"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--calibration FILE.json"), std::string::npos) << r.err;
  EXPECT_TRUE(one_sentence(r.err)) << r.err;
}

TEST(OusterReplay, AnotherSensorsMetadataPublishesNothingAndSaysWhatThePacketsFit) {
  const std::string stream = unique_name("ouster_mismatch");
  StreamGuard guard(stream);
  guard.names.push_back(stream + ".imu");
  const auto r = sim::testing::run({replay_tool, data(dual + ".pcap"), "--calibration", data(legacy + ".json"),
                                    "--stream", stream, "--max-rate", "-q"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("the packets fit RNG19_RFL8_SIG16_NIR16_DUAL with 32 beams"), std::string::npos) << r.err;
  EXPECT_TRUE(one_sentence(r.err)) << r.err;
}

TEST(OusterReplay, AFragmentedCaptureReplaysLikeTheWholeOne) {
  const auto capture = ouster_test::load_capture(dual);
  std::vector<sim::pcap::testing::Record> records;
  std::int64_t t = 1'600'000'000'000'000'000;
  std::uint16_t id = 0;
  for (const auto& payload : capture.lidar) {
    const auto udp = sim::pcap::testing::udp(7502, 7502, payload);
    for (std::size_t offset = 0; offset < udp.size(); offset += 1480) {
      const std::size_t size = std::min<std::size_t>(1480, udp.size() - offset);
      const bool more = offset + size < udp.size();
      sim::pcap::testing::Bytes body(udp.begin() + static_cast<long>(offset), udp.begin() + static_cast<long>(offset + size));
      auto ip = sim::pcap::testing::ipv4({192, 168, 1, 100}, {192, 168, 1, 1}, body, 17, {},
                                         static_cast<std::uint16_t>((more ? 0x2000 : 0) | (offset / 8)));
      ip[4] = static_cast<std::uint8_t>(id >> 8);  // identification
      ip[5] = static_cast<std::uint8_t>(id);
      records.push_back({sim::pcap::testing::ethernet(0x0800, ip), t += 20'000});
    }
    ++id;
  }
  TempDir dir;
  const std::string file = (dir.path / "fragmented.pcap").string();
  sim::pcap::testing::write_capture(file, DLT_EN10MB, records);
  const std::string stream = unique_name("ouster_fragments");
  StreamGuard guard(stream);
  const auto r = sim::testing::run({replay_tool, file, "--calibration", data(dual + ".json"), "--stream", stream,
                                    "--no-imu", "--max-rate", "--summary", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("frames=1 packets=64 lost=0 malformed=0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("skipped=0"), std::string::npos) << r.out;
}

// The capture's lidar packets sent by `senders` sensors (192.168.1.100, .101, …) to the ports
// given, interleaved packet by packet, with its IMU packets from the first sensor on 7503.
std::string several_sensors(const TempDir& dir, const std::string& name, const std::vector<std::uint16_t>& ports) {
  const auto capture = ouster_test::load_capture(dual);
  std::vector<sim::pcap::testing::Record> records;
  std::int64_t t = 1'600'000'000'000'000'000;
  const auto add = [&](std::uint8_t host, std::uint16_t port, const std::vector<std::uint8_t>& payload) {
    const auto ip = sim::pcap::testing::ipv4({192, 168, 1, host}, {192, 168, 1, 1},
                                             sim::pcap::testing::udp(port, port, payload), 17, {}, 0);
    records.push_back({sim::pcap::testing::ethernet(0x0800, ip), t += 20'000});
  };
  for (const auto& payload : capture.lidar) {
    for (std::size_t s = 0; s < ports.size(); ++s) add(static_cast<std::uint8_t>(100 + s), ports[s], payload);
  }
  for (const auto& payload : capture.imu) add(100, 7503, payload);
  const std::string file = (dir.path / name).string();
  sim::pcap::testing::write_capture(file, DLT_EN10MB, records);
  return file;
}

TEST(OusterReplay, SensorsOnOtherPortsThanTheMetadatasAreLeftOutAsOusterSdkDispatchesThem) {
  TempDir dir;
  for (const auto& ports : {std::vector<std::uint16_t>{7502, 7504}, std::vector<std::uint16_t>{7502, 7504, 7506}}) {
    const std::string file = several_sensors(dir, std::to_string(ports.size()) + "_ousters.pcap", ports);
    const std::string stream = unique_name("ouster_ports");
    StreamGuard guard(stream);
    guard.names.push_back(stream + ".imu");
    const auto r = sim::testing::run({replay_tool, file, "--calibration", data(dual + ".json"), "--stream", stream,
                                      "--max-rate", "--summary", "-q"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("frames=1 packets=64 lost=0 malformed=0 imu=10"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("partial_frames_dropped=0"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("duplicate_columns=0"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("skipped=" + std::to_string(64 * (ports.size() - 1))), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("other_senders=0"), std::string::npos) << r.out;
  }
}

TEST(OusterReplay, TwoAndThreeSensorsOnOnePortAreCountedAndWarnedOfOnce) {
  TempDir dir;
  for (std::size_t sensors : {2u, 3u}) {
    const std::string file = several_sensors(dir, std::to_string(sensors) + "_on_one_port.pcap",
                                             std::vector<std::uint16_t>(sensors, 7502));
    const std::string stream = unique_name("ouster_one_port");
    StreamGuard guard(stream);
    guard.names.push_back(stream + ".imu");
    const auto r = sim::testing::run({replay_tool, file, "--calibration", data(dual + ".json"), "--stream", stream,
                                      "--max-rate", "--summary", "-q"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("other_senders=" + std::to_string(64 * (sensors - 1))), std::string::npos) << r.out;
    const std::string warning = "warning: packets from 192.168.1.101 are decoded besides those from 192.168.1.100";
    ASSERT_NE(r.err.find(warning), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(warning), r.err.rfind(warning)) << "said once: " << r.err;
    // The user's way out: keep one sensor.
    const auto one = sim::testing::run({replay_tool, file, "--calibration", data(dual + ".json"), "--stream", stream,
                                        "--max-rate", "--summary", "-q", "--filter", "src host 192.168.1.100"});
    ASSERT_EQ(one.code, 0) << one.err;
    EXPECT_NE(one.out.find("frames=1 packets=64 lost=0"), std::string::npos) << one.out;
    EXPECT_NE(one.out.find("other_senders=0"), std::string::npos) << one.out;
  }
}

using lidar_test::FakeSensorHttp;

void send_to(std::uint16_t port, const std::vector<std::vector<std::uint8_t>>& payloads,
             const char* address = "127.0.0.1") {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  ::inet_pton(AF_INET, address, &to.sin_addr);
  for (const auto& p : payloads) {
    (void)::sendto(fd, p.data(), p.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  }
  ::close(fd);
}

struct Ports {
  unsigned lidar = 0, imu = 0;
};
std::optional<Ports> listening(Process& p) {
  auto line = p.wait_for_line("listening on");
  if (!line) return std::nullopt;
  Ports ports;
  if (std::sscanf(line->c_str(), "sim_lidar_ouster: listening on %*s lidar port %u imu port %u", &ports.lidar,
                  &ports.imu) != 2) {
    return std::nullopt;
  }
  return ports;
}

TEST(OusterLive, MetadataComesFromTheSensorsHttpApiIsCachedAndTheFramesAndImuArePublished) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto capture = ouster_test::load_capture(dual);
  TempDir dir;
  const std::string cache = (dir.path / "os0.json").string();
  const std::string stream = unique_name("ouster_live");
  StreamGuard guard(stream);
  guard.names.push_back(stream + ".imu");
  {
    FakeSensorHttp sensor(ouster_test::read_text(ouster_test::data_path(dual + ".json")));
    Process driver({live_tool, "--metadata-from-sensor", "--sensor-ip", "127.0.0.1", "--http-port",
                    std::to_string(sensor.port()), "--calibration", cache, "--lidar-port", "0", "--imu-port",
                    "0", "--stream", stream, "--status-interval", "0", "--summary", "--frame-id", "os_sensor"});
    const auto ports = listening(driver);
    ASSERT_TRUE(ports) << driver.err();
    EXPECT_EQ(sensor.requests_for("/api/v1/sensor/metadata"), 1);  // (the clock poll asks too)
    EXPECT_EQ(ouster_test::read_text(cache), ouster_test::read_text(ouster_test::data_path(dual + ".json")));
    auto reader = sim::testing::wait_for_stream(stream);
    ASSERT_TRUE(reader);
    send_to(static_cast<std::uint16_t>(ports->imu), capture.imu);
    send_to(static_cast<std::uint16_t>(ports->lidar), capture.lidar);
    std::vector<std::byte> buffer(reader->capacity());
    sim::FrameInfo info;
    ASSERT_EQ(reader->read_next(buffer, info, 30s), sim::ReadStatus::new_frame) << driver.err();
    EXPECT_EQ(info.size, 65536 * sizeof(sim::LidarPoint));
    auto described = reader->sensor_info();
    ASSERT_TRUE(described && *described);
    EXPECT_EQ((*described)->identity.model, "OS-0-32-U1");
    EXPECT_EQ((*described)->frame_id, "os_sensor");
    EXPECT_EQ((*described)->point_time, sim::PointTime::after_frame_stamp);
    ::kill(driver.pid(), SIGTERM);
    EXPECT_EQ(driver.wait(), 0) << driver.err();
    EXPECT_NE(driver.out().find("frames=1 packets=64 lost=0 malformed=0 imu=10"), std::string::npos) << driver.out();
  }
  // The sensor is gone: the cached metadata is used, with a warning.
  Process again({live_tool, "--metadata-from-sensor", "--sensor-ip", "127.0.0.1", "--http-port", "1",
                 "--http-timeout", "2", "--calibration", cache, "--lidar-port", "0", "--imu-port", "0",
                 "--stream", stream, "--status-interval", "0"});
  ASSERT_TRUE(listening(again)) << again.err();
  ::kill(again.pid(), SIGTERM);
  EXPECT_EQ(again.wait(), 0);
  EXPECT_NE(again.err().find("using the cached " + cache), std::string::npos) << again.err();
  // Without a cache it is one sentence and exit 1.
  const auto none = sim::testing::run({live_tool, "--metadata-from-sensor", "--sensor-ip", "127.0.0.1",
                                       "--http-port", "1", "--http-timeout", "2", "--calibration",
                                       (dir.path / "absent.json").string(), "--stream", unique_name("ouster_none")});
  EXPECT_EQ(none.code, 1);
  EXPECT_NE(none.err.find("no cached metadata"), std::string::npos) << none.err;
  EXPECT_TRUE(one_sentence(none.err)) << none.err;
}

// A sensor reconfigured from its web page (or restarted) sends packets of a new initialization
// id: with --metadata-from-sensor, once for 2 s every lidar packet was refused so, the driver
// fetches the metadata again and publishes the sensor's frames (review turn 4, L6).
TEST(OusterLive, AReconfiguredSensorsMetadataIsFetchedAgainAndItsFramesPublished) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto capture = ouster_test::load_capture(dual);
  const std::string now = ouster_test::read_text(ouster_test::data_path(dual + ".json"));
  std::string before = now;  // the metadata of the sensor before its reconfiguration
  const std::size_t id = before.find("9599938");
  ASSERT_NE(id, std::string::npos);
  before.replace(id, 7, "9599937");
  TempDir dir;
  const std::string stream = unique_name("ouster_reconfigured");
  StreamGuard guard(stream);
  FakeSensorHttp sensor(before);
  Process driver({live_tool, "--metadata-from-sensor", "--sensor-ip", "localhost", "--http-port",
                  std::to_string(sensor.port()), "--calibration", (dir.path / "os0.json").string(), "--lidar-port",
                  "0", "--imu-port", "0", "--no-imu", "--clock-poll-seconds", "0", "--stream", stream,
                  "--status-interval", "0", "--summary"});
  auto ports = listening(driver);
  ASSERT_TRUE(ports) << driver.err();
  sensor.set_route("/api/v1/sensor/metadata", 200, now);  // reconfigured: packets of 9599938
  // The sensor sends; the driver refuses its packets until it has the new metadata.
  std::optional<std::string> again;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!again && std::chrono::steady_clock::now() < deadline) {
    send_to(static_cast<std::uint16_t>(ports->lidar), capture.lidar);
    again = driver.wait_for_line("listening on", 200ms);
  }
  ASSERT_TRUE(again) << driver.err();
  EXPECT_EQ(sensor.requests_for("/api/v1/sensor/metadata"), 2);
  ASSERT_EQ(std::sscanf(again->c_str(), "sim_lidar_ouster: listening on %*s lidar port %u imu port %u", &ports->lidar,
                        &ports->imu),
            2);
  auto reader = sim::testing::wait_for_stream(stream);
  ASSERT_TRUE(reader);
  send_to(static_cast<std::uint16_t>(ports->lidar), capture.lidar);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  EXPECT_EQ(reader->read_next(buffer, info, 30s), sim::ReadStatus::new_frame) << driver.err();
  ::kill(driver.pid(), SIGTERM);
  EXPECT_EQ(driver.wait(), 0) << driver.err();
  EXPECT_NE(driver.err().find("another initialization id than the metadata's (9599937)"), std::string::npos)
      << driver.err();
  EXPECT_NE(driver.err().find("fetching its metadata again"), std::string::npos) << driver.err();
  EXPECT_NE(driver.out().find("frames=1 packets=64 "), std::string::npos) << driver.out();
}

// The stream says which clock the sensor stamps with: the metadata's timestamp_mode (PTP here;
// the captures' metadata give none, and then the time base is unknown and the sentence says why).
// Odd bytes in the metadata's text never stop the driver.
TEST(OusterLive, TheStreamSaysWhichClockTheSensorStampsWithFromItsTimestampMode) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  TempDir dir;
  std::string json = ouster_test::read_text(data(legacy + ".json"));
  const std::size_t open = json.find('{');
  ASSERT_NE(open, std::string::npos);
  json.insert(open + 1, "\"config_params\": {\"timestamp_mode\": \"TIME_FROM_PTP_1588\"}, ");
  const fs::path ptp = dir.path / "ptp.json";
  std::ofstream(ptp) << json;
  // A mode and a product line with a control character are shown with a '?' in its place (the
  // description would refuse the character): the driver still starts.
  json.replace(json.find("TIME_FROM_PTP_1588"), 18, "TIME_\\u0001X");
  json.replace(json.find("\"OS-1-32-G\""), 11, "\"OS-1\\u0007-32-G\"");
  const fs::path odd = dir.path / "odd.json";
  std::ofstream(odd) << json;
  struct Case {
    std::string metadata;
    sim::TimeBase time_base;
    std::string time_sync;
    std::string model = "OS-1-32-G";
  };
  const std::vector<Case> cases = {
      {ptp.string(), sim::TimeBase::sensor_synchronized,
       "PTP (timestamp_mode TIME_FROM_PTP_1588; whether it is locked is not read)"},
      {data(legacy + ".json"), sim::TimeBase::unknown,
       "the sensor's clock; the metadata does not give its timestamp_mode"},
      {odd.string(), sim::TimeBase::unknown, "the sensor's clock, timestamp_mode TIME_?X (not known to this driver)",
       "OS-1?-32-G"},
  };
  for (const Case& expected : cases) {
    const std::string stream = unique_name("ouster_live_clock");
    StreamGuard guard(stream);
    Process driver({live_tool, "--calibration", expected.metadata, "--lidar-port", "0", "--imu-port", "0", "--no-imu",
                    "--stream", stream, "--status-interval", "0"});
    ASSERT_TRUE(listening(driver)) << driver.err();
    auto reader = sim::testing::wait_for_stream(stream);
    ASSERT_TRUE(reader);
    auto described = reader->sensor_info();
    ASSERT_TRUE(described && *described);
    EXPECT_EQ((*described)->time_base, expected.time_base);
    EXPECT_EQ((*described)->time_sync, expected.time_sync);
    EXPECT_EQ((*described)->identity.model, expected.model);
    ::kill(driver.pid(), SIGTERM);
    EXPECT_EQ(driver.wait(), 0) << driver.err();
  }
}

TEST(OusterLive, PacketsThatDoNotFitTheMetadataAreCountedAndToldOnceNeverPublished) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto capture = ouster_test::load_capture(dual);
  const std::string stream = unique_name("ouster_live_mismatch");
  StreamGuard guard(stream);
  Process driver({live_tool, "--calibration", data(legacy + ".json"), "--lidar-port", "0", "--imu-port", "0",
                  "--no-imu", "--stream", stream, "--status-interval", "0", "--summary"});
  const auto ports = listening(driver);
  ASSERT_TRUE(ports) << driver.err();
  auto reader = sim::testing::wait_for_stream(stream);
  ASSERT_TRUE(reader);
  send_to(static_cast<std::uint16_t>(ports->lidar), capture.lidar);
  // Then a datagram larger than any Ouster packet: counted, not cut to a plausible size.
  send_to(static_cast<std::uint16_t>(ports->lidar), {std::vector<std::uint8_t>(65000, 0)});
  // Wait until the driver has taken them all: its one sentence comes with the first.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (driver.err().find("the packets fit") == std::string::npos && std::chrono::steady_clock::now() < deadline) {
    (void)driver.next_line(100ms);
  }
  std::this_thread::sleep_for(200ms);  // the rest of the burst; the counts below do not depend on it
  ::kill(driver.pid(), SIGTERM);
  EXPECT_EQ(driver.wait(), 0);
  EXPECT_NE(driver.err().find("the packets fit RNG19_RFL8_SIG16_NIR16_DUAL with 32 beams"), std::string::npos)
      << driver.err();
  std::size_t told = 0;
  for (std::size_t at = 0; (at = driver.err().find("the packets fit", at)) != std::string::npos; ++at) ++told;
  EXPECT_EQ(told, 1u) << driver.err();
  EXPECT_NE(driver.out().find("frames=0 packets=0"), std::string::npos) << driver.out();
  sim::FrameInfo info;
  std::vector<std::byte> buffer(reader->capacity());
  EXPECT_NE(reader->read_next(buffer, info, 0ms), sim::ReadStatus::new_frame);
}

// Two sensors multicasting to two groups on one port, a driver for each: each driver publishes
// its own sensor's frames only (Linux would hand both groups to both sockets by default).
TEST(OusterLive, TwoDriversOnOnePortWithTwoGroupsEachPublishOnlyTheirGroup) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto capture = ouster_test::load_capture(dual);
  const std::array<const char*, 2> groups{"239.201.201.1", "239.201.201.2"};
  std::vector<std::string> streams{unique_name("ouster_group_a"), unique_name("ouster_group_b")};
  StreamGuard guard_a(streams[0]);
  StreamGuard guard_b(streams[1]);
  std::vector<std::unique_ptr<Process>> drivers;
  std::string port = "0";
  for (std::size_t d = 0; d < 2; ++d) {
    drivers.push_back(std::make_unique<Process>(std::vector<std::string>{
        live_tool, "--calibration", data(dual + ".json"), "--lidar-port", port, "--imu-port", "0", "--no-imu",
        "--multicast", groups[d], "--stream", streams[d], "--summary", "--status-interval", "0"}));
    const auto ports = listening(*drivers[d]);
    ASSERT_TRUE(ports) << drivers[d]->err();
    port = std::to_string(ports->lidar);
  }
  auto reader_a = sim::testing::wait_for_stream(streams[0]);
  auto reader_b = sim::testing::wait_for_stream(streams[1]);
  ASSERT_TRUE(reader_a && reader_b);
  send_to(static_cast<std::uint16_t>(std::stoi(port)), capture.lidar, groups[0]);
  std::vector<std::byte> buffer(reader_a->capacity());
  sim::FrameInfo info;
  EXPECT_EQ(reader_a->read_next(buffer, info, 30s), sim::ReadStatus::new_frame) << drivers[0]->err();
  for (auto& driver : drivers) {
    ::kill(driver->pid(), SIGTERM);
    EXPECT_EQ(driver->wait(), 0) << driver->err();
  }
  EXPECT_NE(drivers[0]->out().find("packets=64 "), std::string::npos) << drivers[0]->out();
  EXPECT_NE(drivers[1]->out().find("frames=0 packets=0 "), std::string::npos) << drivers[1]->out();
  EXPECT_NE(drivers[1]->out().find(" datagrams=0 "), std::string::npos) << drivers[1]->out();
}

TEST(OusterLive, AMulticastGroupIsJoinedAndPacketsOfAnotherSenderAreIgnored) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto capture = ouster_test::load_capture(dual);
  for (bool filtered : {false, true}) {
    const std::string stream = unique_name("ouster_multicast");
    StreamGuard guard(stream);
    std::vector<std::string> argv = {live_tool, "--calibration", data(dual + ".json"), "--lidar-port", "0",
                                     "--imu-port", "0", "--no-imu", "--multicast", "239.201.201.201",
                                     "--stream", stream, "--summary", "--status-interval",
                                     filtered ? "0.05" : "0"};
    if (filtered) {
      // The packets come from 127.0.0.1; the status lines (in a log: one per tick) count them.
      argv.insert(argv.end(), {"--source", "127.0.0.2"});
    }
    Process driver(argv);
    const auto ports = listening(driver);
    ASSERT_TRUE(ports) << driver.err();
    auto reader = sim::testing::wait_for_stream(stream);
    ASSERT_TRUE(reader);
    send_to(static_cast<std::uint16_t>(ports->lidar), capture.lidar, "239.201.201.201");
    std::vector<std::byte> buffer(reader->capacity());
    sim::FrameInfo info;
    if (!filtered) {
      EXPECT_EQ(reader->read_next(buffer, info, 30s), sim::ReadStatus::new_frame) << driver.err();
    } else {
      const std::string all = "other-source " + std::to_string(capture.lidar.size());
      const auto deadline = std::chrono::steady_clock::now() + 30s;  // a hang guard
      while (driver.err().find(all) == std::string::npos && std::chrono::steady_clock::now() < deadline) {
        (void)driver.next_line(50ms);
      }
      EXPECT_NE(driver.err().find(all), std::string::npos) << driver.err();
      EXPECT_NE(reader->read_next(buffer, info, 0ms), sim::ReadStatus::new_frame);
    }
    ::kill(driver.pid(), SIGTERM);
    EXPECT_EQ(driver.wait(), 0) << driver.err();
    if (filtered) {
      EXPECT_NE(driver.out().find("frames=0 packets=0"), std::string::npos) << driver.out();
      EXPECT_NE(driver.out().find("other_source=64"), std::string::npos) << driver.out();
    } else {
      EXPECT_NE(driver.out().find("frames=1 packets=64"), std::string::npos) << driver.out();
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::on);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
