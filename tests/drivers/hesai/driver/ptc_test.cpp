// SPDX-License-Identifier: Apache-2.0
// Calibration from the sensor over PTC, against a small fake sensor in this process: a real TCP
// server on loopback (port 0) that serves the recorded QT128 calibration file, or misbehaves
// the ways a network and a sensor can (refuses, closes halfway, answers garbage, stalls, says
// no). Each failure must be one sentence, none may hang (short deadlines), and the driver must
// cache what it fetched and fall back to the cache with a warning.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "fake_ptc_sensor.hpp"
#include "sim/hesai/ptc_client.hpp"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using sim::hesai::Model;
using sim::testing::Process;
using sim::testing::run;

const fs::path data_dir = SIM_HESAI_TEST_DATA;
const std::string live_tool = SIM_LIDAR_HESAI;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const std::string qt128_csv = read_file(data_dir / "pandarqt128.calibration.csv");
const std::string xt32_csv = read_file(data_dir / "pandarxt32.calibration.csv");

using hesai_test::Behaviour;
using hesai_test::closed_port;
using hesai_test::FakeSensor;

sim::hesai::PtcEndpoint endpoint(std::uint16_t port) {
  sim::hesai::PtcEndpoint e;
  e.host = "127.0.0.1";
  e.port = port;
  e.timeout = 400ms;
  return e;
}

struct TempDir {
  fs::path path = fs::temp_directory_path() /
                  ("sim_hesai_ptc_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
  static int& counter() {
    static int c = 0;
    return c;
  }
};

void expect_one_sentence(const std::string& message, const std::string& must_contain) {
  EXPECT_FALSE(message.empty());
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(must_contain), std::string::npos) << message;
  EXPECT_NE(message.find("127.0.0.1"), std::string::npos) << "names the sensor: " << message;
}

}  // namespace

TEST(PtcCalibration, FetchesTheSensorsFileAndCachesIt) {
  FakeSensor sensor(Behaviour::serve);
  auto text = sim::hesai::fetch_calibration_text(endpoint(sensor.port()));
  ASSERT_TRUE(text) << text.error().message;
  EXPECT_EQ(*text, qt128_csv);

  TempDir dir;
  const fs::path cache = dir.path / "sub" / "unit.csv";
  auto fetched = sim::hesai::calibration_from_sensor(endpoint(sensor.port()), cache, Model::pandar_qt128);
  ASSERT_TRUE(fetched) << fetched.error().message;
  EXPECT_FALSE(fetched->from_cache);
  EXPECT_EQ(fetched->channels, 128u);
  EXPECT_EQ(read_file(cache), qt128_csv);
  EXPECT_FALSE(fs::exists(cache.string() + ".part"));
  EXPECT_EQ(sensor.requests(), 2);
}

TEST(PtcCalibration, EveryMisbehaviourIsOneSentenceAndNeverAHang) {
  {
    const auto r = sim::hesai::fetch_calibration_text(endpoint(closed_port()));
    ASSERT_FALSE(r);
    expect_one_sentence(r.error().message, "refused the PTC connection");
  }
  const std::vector<std::pair<Behaviour, std::string>> cases{
      {Behaviour::truncate, "closed the PTC connection after"},
      {Behaviour::garbage, "not Hesai PTC"},
      {Behaviour::stall, "stopped sending after 108 bytes"},
      {Behaviour::silent, "did not answer within 0.4 s"},
      {Behaviour::refuse_request, "PTC return code 3"},
  };
  for (const auto& [behaviour, words] : cases) {
    FakeSensor sensor(behaviour);
    const auto r = sim::hesai::fetch_calibration_text(endpoint(sensor.port()));
    ASSERT_FALSE(r) << words;
    expect_one_sentence(r.error().message, words);
  }
  // A name that never resolves (.invalid, RFC 6761): one sentence, before any connection.
  sim::hesai::PtcEndpoint nonsense = endpoint(1);
  nonsense.host = "lidar.invalid";
  const auto r = sim::hesai::fetch_calibration_text(nonsense);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("'lidar.invalid' (--sensor-ip)"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("resolve"), std::string::npos) << r.error().message;
}

TEST(PtcCalibration, FallsBackToTheCacheWithAWarningAndFailsWithoutOne) {
  TempDir dir;
  const fs::path cache = dir.path / "unit.csv";
  {
    FakeSensor sensor(Behaviour::serve);
    ASSERT_TRUE(sim::hesai::calibration_from_sensor(endpoint(sensor.port()), cache, Model::pandar_qt128));
  }
  {  // the sensor is off
    auto r = sim::hesai::calibration_from_sensor(endpoint(closed_port()), cache, Model::pandar_qt128);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->from_cache);
    EXPECT_EQ(r->channels, 128u);
    EXPECT_NE(r->warning.find("using the cached " + cache.string()), std::string::npos) << r->warning;
  }
  {  // the sensor serves a file that is not a QT128's: checked, not cached, cache used
    FakeSensor sensor(Behaviour::serve, xt32_csv);
    auto r = sim::hesai::calibration_from_sensor(endpoint(sensor.port()), cache, Model::pandar_qt128);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->from_cache);
    EXPECT_NE(r->warning.find("32"), std::string::npos) << r->warning;
    EXPECT_EQ(read_file(cache), qt128_csv);
  }
  {  // garbage text inside a well-formed answer
    FakeSensor sensor(Behaviour::serve, std::string("\x01\x02 not a csv", 12));
    auto r = sim::hesai::calibration_from_sensor(endpoint(sensor.port()), cache, Model::pandar_qt128);
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->from_cache);
  }
  {  // nothing to fall back on
    FakeSensor sensor(Behaviour::stall);
    auto r = sim::hesai::calibration_from_sensor(endpoint(sensor.port()), dir.path / "none.csv",
                                                 Model::pandar_qt128);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find("no cached calibration at"), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  }
}

TEST(PtcCalibration, TheDriversStreamCarriesTheUnitsIdentityFromPtc) {
  TempDir dir;
  const std::string cache = (dir.path / "qt128.csv").string();
  const std::string stream = "/test_hesai_ptc_id_" + std::to_string(::getpid());
  FakeSensor sensor(Behaviour::serve);
  Process driver({live_tool, "--calibration-from-sensor", "--sensor-ip", "127.0.0.1",
                  "--ptc-port", std::to_string(sensor.port()), "--ptc-timeout", "2",
                  "--calibration", cache, "--model", "PandarQT128", "--port", "0", "--bind",
                  "127.0.0.1", "--stream", stream, "--status-interval", "0", "--frame-id",
                  "lidar_front", "--y", "0.5"});
  ASSERT_TRUE(driver.wait_for_line("listening on")) << driver.err();
  // The model is given: the stream is created right after the port is opened.
  auto reader = sim::Reader::open(stream);
  for (int i = 0; i < 3000 && !reader; ++i) {
    std::this_thread::sleep_for(10ms);
    reader = sim::Reader::open(stream);
  }
  ASSERT_TRUE(reader) << reader.error().message << driver.err();
  auto info = reader->sensor_info();
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  const sim::SensorInfo& s = **info;
  EXPECT_EQ(s.frame_id, "lidar_front");
  ASSERT_TRUE(s.mounting.has_value());
  EXPECT_EQ(s.mounting->translation[1], 0.5);
  EXPECT_EQ(s.identity.vendor, "Hesai");
  EXPECT_EQ(s.identity.model, "PandarQT128");
  EXPECT_EQ(s.identity.serial, "QT12800TEST01");
  EXPECT_EQ(s.identity.firmware, "SENS-3.2.9, control CTRL-1.4.2");
  EXPECT_EQ(s.calibration_source, "sensor 127.0.0.1 over PTC");
  EXPECT_EQ(s.point_time, sim::PointTime::after_frame_stamp);
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(), 0) << driver.err();
  (void)sim::destroy(stream, true);
}

TEST(PtcCalibration, AnInventoryAnswerIsReadAndAShortOneRefused) {
  const std::string payload = FakeSensor::inventory();
  const auto bytes = std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size());
  auto inventory = sim::hesai::ptc::parse_inventory(bytes);
  ASSERT_TRUE(inventory) << inventory.error().message;
  EXPECT_EQ(inventory->serial, "QT12800TEST01");
  EXPECT_EQ(inventory->manufactured, "2024-03-01");
  EXPECT_EQ(inventory->software, "3.1.8");
  EXPECT_EQ(inventory->sensor_firmware, "SENS-3.2.9");
  EXPECT_EQ(inventory->model_code, 32);
  EXPECT_EQ(inventory->lines, 128);
  auto short_answer = sim::hesai::ptc::parse_inventory(bytes.first(60));
  ASSERT_FALSE(short_answer);
  EXPECT_NE(short_answer.error().message.find("shorter"), std::string::npos);
}

TEST(PtcCalibration, DriverFetchesAtStartAndFallsBackToItsCache) {
  TempDir dir;
  const std::string cache = (dir.path / "qt128.csv").string();
  const std::string stream = "/test_hesai_ptc_" + std::to_string(::getpid());
  auto driver_args = [&](std::uint16_t ptc_port) {
    return std::vector<std::string>{live_tool, "--calibration-from-sensor", "--sensor-ip",
                                    "127.0.0.1", "--ptc-port", std::to_string(ptc_port),
                                    "--ptc-timeout", "0.4", "--calibration", cache, "--model",
                                    "PandarQT128", "--port", "0", "--bind", "127.0.0.1",
                                    "--stream", stream, "--status-interval", "0"};
  };
  {
    FakeSensor sensor(Behaviour::serve);
    Process driver(driver_args(sensor.port()));
    ASSERT_TRUE(driver.wait_for_line("listening on")) << driver.err();
    driver.signal(SIGTERM);
    ASSERT_EQ(driver.wait(), 0) << driver.err();
    EXPECT_NE(driver.out().find("fetched and cached in " + cache), std::string::npos) << driver.out();
    EXPECT_EQ(read_file(cache), qt128_csv);
  }
  {
    Process driver(driver_args(closed_port()));
    ASSERT_TRUE(driver.wait_for_line("listening on")) << driver.err();
    driver.signal(SIGTERM);
    ASSERT_EQ(driver.wait(), 0) << driver.err();
    EXPECT_NE(driver.err().find("warning: sensor 127.0.0.1:"), std::string::npos) << driver.err();
    EXPECT_NE(driver.err().find("using the cached " + cache + "."), std::string::npos) << driver.err();
  }
  fs::remove(cache);
  {
    FakeSensor sensor(Behaviour::silent);
    const auto r = run(driver_args(sensor.port()));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("no cached calibration at " + cache), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
  }
  auto bad_ip = driver_args(1);
  bad_ip[3] = "not a sensor";  // neither an address nor a host name: a usage error
  const auto bad = run(bad_ip);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("'not a sensor' is neither an address"), std::string::npos) << bad.err;
  (void)sim::destroy(stream, true);  // cleanup: a stream already gone is fine
}
