// SPDX-License-Identifier: Apache-2.0
// sim_echo, sim_ls and sim_rm run as real processes against real streams.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sys/stat.h>
#include <memory>
#include <optional>
#include <thread>
#include <unistd.h>

#include "sim/sim.hpp"
#include "sim_test/process.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using sim::testing::Process;
using test::StreamGuard;
using test::unique_name;

namespace {

const std::string kPeer = SIM_TEST_PEER;
const std::string kEcho = SIM_ECHO;
const std::string kLs = SIM_LS;
const std::string kRm = SIM_RM;

std::unique_ptr<Process> start_writer(const std::string& name, int frames, double rate,
                                      int linger_ms) {
  auto child = std::make_unique<Process>(std::vector<std::string>{
      kPeer, "writer", name, std::to_string(frames), std::to_string(rate), "64", "1024",
      std::to_string(linger_ms)});
  EXPECT_EQ(child->next_line().value_or("").rfind("ready", 0), 0u);
  return child;
}

double json_number(const std::string& line, const std::string& key) {
  const auto at = line.find("\"" + key + "\":");
  if (at == std::string::npos) return -1;
  return std::stod(line.substr(at + key.size() + 3));
}

}  // namespace

TEST(SimEcho, PrintsOneJsonLinePerFrameWithJson) {
  StreamGuard g{unique_name("echo")};
  auto writer = start_writer(g.name, 1000000, 100, 0);
  Process echo({kEcho, g.name, "--count", "5", "--json"});
  std::uint64_t previous = 0;
  for (int i = 0; i < 5; ++i) {
    const std::string line = echo.next_line().value_or("");
    ASSERT_TRUE(line.starts_with('{')) << line << echo.err();
    const auto seq = static_cast<std::uint64_t>(json_number(line, "seq"));
    EXPECT_GT(seq, previous);
    previous = seq;
    EXPECT_GE(json_number(line, "size"), 64);
    EXPECT_GE(json_number(line, "latency_us"), 0);
    EXPECT_NE(line.find("\"layout\":\"bytes\""), std::string::npos);
  }
  EXPECT_EQ(echo.wait(), 0);
}

TEST(SimEcho, PrintsReadableLinesForPeople) {
  StreamGuard g{unique_name("echotext")};
  auto writer = start_writer(g.name, 1000000, 100, 0);
  Process echo({kEcho, g.name, "--count", "2"});
  const std::string line = echo.next_line().value_or("");
  EXPECT_TRUE(line.starts_with("seq ")) << line << echo.err();
  EXPECT_NE(line.find(" latency "), std::string::npos) << line;
  EXPECT_EQ(echo.wait(), 0);
}

// What a user relies on from --stats: every frame published while it listened is accounted
// for (read, or skipped because a newer one replaced it first), and the rate and intervals are
// measured. Whether a process stall made it skip some is scheduling luck, so it is not asserted.
TEST(SimEcho, StatsAccountForEveryFramePublishedWhileListening) {
  StreamGuard g{unique_name("echostats")};
  // sim_echo must be listening before the first frame: create the stream, wait until sim_echo
  // sleeps on it, then hand the stream to the writer process.
  std::optional<Writer> creator = Writer::create({.name = g.name, .capacity = 1024}).value();
  Process echo({kEcho, g.name, "--stats", "--json", "--interval", "0.1"});
  for (int i = 0; i < 1000 && inspect(g.name)->sleeping_readers == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  creator.reset();
  auto writer = start_writer(g.name, 100, 100, 60000);
  ASSERT_TRUE(writer->wait_for_line("done").has_value());
  // The newest frame is always readable: sim_echo reaches seq 100 whatever it skipped.
  ASSERT_TRUE(echo.wait_for_line("\"last_seq\":100,").has_value()) << echo.err();
  echo.signal(SIGINT);
  std::string summary;
  while (const auto line = echo.next_line()) {
    if (line->find("\"summary\"") != std::string::npos) summary = *line;
  }
  ASSERT_EQ(echo.wait(), 0) << echo.err();
  ASSERT_FALSE(summary.empty()) << echo.out();
  EXPECT_EQ(json_number(summary, "frames") + json_number(summary, "skipped"), 100) << summary;
  EXPECT_EQ(json_number(summary, "last_seq"), 100) << summary;
  EXPECT_GT(json_number(summary, "rate_hz"), 0) << summary;
  const auto interval = summary.substr(summary.find("\"interval_ms\""));
  EXPECT_GE(json_number(interval, "max"), json_number(interval, "min")) << summary;
}

TEST(SimEcho, StatsIgnoreAFramePublishedBeforeItStarted) {
  StreamGuard g{unique_name("echoold")};
  auto writer = start_writer(g.name, 1, 1000, 60000);
  ASSERT_TRUE(writer->wait_for_line("done").has_value());
  Process echo({kEcho, g.name, "--stats", "--json"});
  for (int i = 0; i < 1000 && inspect(g.name)->sleeping_readers == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  echo.signal(SIGTERM);
  ASSERT_EQ(echo.wait(), 0) << echo.err();
  const auto at = echo.out().find("\"summary\"");
  ASSERT_NE(at, std::string::npos) << echo.out();
  EXPECT_EQ(json_number(echo.out().substr(at), "frames"), 0) << echo.out();
}

TEST(SimEcho, StopsOnSigtermWhileWaitingForAStreamThatNeverComes) {
  Process echo({kEcho, unique_name("nevercomes"), "--wait-for-stream"});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  echo.signal(SIGTERM);
  EXPECT_EQ(echo.wait(), 0) << echo.err();
  EXPECT_FALSE(echo.deadline_passed());
}

TEST(SimEcho, AMissingStreamOrBadOptionGivesAnExitCodeScriptsCanTrust) {
  Process missing({kEcho, unique_name("missing")});
  EXPECT_EQ(missing.wait(), 1);
  Process bad_name({kEcho, "no-slash"});
  EXPECT_EQ(bad_name.wait(), 2);
  Process bad_option({kEcho, "/x", "--no-such-option"});
  EXPECT_EQ(bad_option.wait(), 2);
  Process help({kEcho, "--help"});
  EXPECT_EQ(help.wait(), 0);
  EXPECT_NE(help.out().find("--stats"), std::string::npos);
}

TEST(SimLs, ListsAStreamWithItsWriter) {
  StreamGuard g{unique_name("ls")};
  auto writer = start_writer(g.name, 10, 1000, 60000);
  EXPECT_EQ(writer->next_line().value_or("").rfind("done", 0), 0u);
  Process ls({kLs, "--json"});  // every stream on the machine, this test's among them
  ls.wait();
  const std::string out = ls.out();
  std::string mine;
  std::size_t start = 0;
  while (start < out.size()) {
    const std::size_t end = out.find('\n', start);
    const std::string line = out.substr(start, end - start);
    if (line.find("\"name\":\"" + g.name + "\"") != std::string::npos) mine = line;
    start = end == std::string::npos ? out.size() : end + 1;
  }
  ASSERT_FALSE(mine.empty()) << out;
  EXPECT_EQ(json_number(mine, "frames"), 10);
  EXPECT_EQ(json_number(mine, "capacity"), 1024);
  EXPECT_NE(mine.find("\"writer_alive\":true"), std::string::npos);
  EXPECT_EQ(json_number(mine, "writer_pid"), writer->pid());
}

TEST(SimRm, KeepsLiveStreamsUnlessForcedAndClearsDeadOnes) {
  StreamGuard alive{unique_name("rmalive")};
  StreamGuard dead{unique_name("rmdead")};
  auto writer = start_writer(alive.name, 1, 1000, 60000);
  { ASSERT_TRUE(Writer::create({.name = dead.name, .capacity = 64})); }

  Process refused({kRm, alive.name});
  EXPECT_EQ(refused.wait(), 1);
  EXPECT_TRUE(Reader::open(alive.name));

  Process sweep({kRm, "--dead", alive.name, dead.name});
  EXPECT_EQ(sweep.wait(), 0);
  EXPECT_TRUE(Reader::open(alive.name));
  EXPECT_EQ(Reader::open(dead.name).error().code, ErrorCode::not_found);

  Process forced({kRm, "--force", alive.name});
  EXPECT_EQ(forced.wait(), 0);
  EXPECT_EQ(Reader::open(alive.name).error().code, ErrorCode::not_found);

  Process nothing({kRm});
  EXPECT_EQ(nothing.wait(), 2);
}

TEST(SimLs, ListsOnlyTheStreamsNamedAndFailsOnAMissingOne) {
  StreamGuard g{unique_name("lsnamed")};
  StreamGuard other{unique_name("lsother")};
  auto writer = start_writer(g.name, 3, 1000, 60000);
  EXPECT_EQ(writer->next_line().value_or("").rfind("done", 0), 0u);
  { ASSERT_TRUE(Writer::create({.name = other.name, .capacity = 64})); }

  Process ls({kLs, "--json", "--window", "0", g.name});
  EXPECT_EQ(ls.wait(), 0) << ls.err();
  EXPECT_NE(ls.out().find("\"name\":\"" + g.name + "\""), std::string::npos) << ls.out();
  EXPECT_EQ(ls.out().find(other.name), std::string::npos) << ls.out();
  EXPECT_EQ(std::count(ls.out().begin(), ls.out().end(), '\n'), 1) << ls.out();

  const std::string missing = unique_name("lsmissing");
  Process absent({kLs, "--window", "0", g.name, missing});
  EXPECT_EQ(absent.wait(), 1);
  EXPECT_NE(absent.out().find(missing), std::string::npos) << absent.out();

  Process bad({kLs, "no_slash"});
  EXPECT_EQ(bad.wait(), 2);
}

TEST(SimLs, ShowsTheWritersProgramNameUntruncated) {
  // A copy of the peer under a name longer than the kernel's 15-character process name.
  const std::string long_name = "/tmp/sim_test_peer_with_a_long_name_" + std::to_string(getpid());
  ASSERT_EQ(std::system(("cp " + kPeer + " " + long_name).c_str()), 0);
  StreamGuard g{unique_name("lslong")};
  {
    Process writer({long_name, "writer", g.name, "1", "1000", "64", "1024", "60000"});
    ASSERT_TRUE(writer.wait_for_line("done").has_value());
    // Named: other tests' streams (a fuzzer's garbage region, say) are not this test's business.
    Process ls({kLs, "--json", "--window", "0", g.name});
    EXPECT_EQ(ls.wait(), 0) << ls.err();
    const std::string expected = long_name.substr(5);
    EXPECT_NE(ls.out().find("\"writer\":\"" + expected + "\""), std::string::npos) << ls.out();
  }
  std::remove(long_name.c_str());
}

TEST(SimLs, WatchShowsTheRateOfALiveStreamAndStopsOnSigint) {
  StreamGuard g{unique_name("lswatch")};
  auto writer = start_writer(g.name, 1000000, 1000, 0);
  Process ls({kLs, "--watch", "--json", "--interval", "0.1"});
  std::optional<std::string> line;
  // A refresh after the view's reader has watched a window of the writer's frames.
  while ((line = ls.wait_for_line("\"name\":\"" + g.name + "\""))) {
    if (json_number(*line, "rate_hz") > 0 && json_number(*line, "bandwidth_bytes_per_s") > 0) break;
  }
  ASSERT_TRUE(line.has_value()) << ls.err();
  EXPECT_NE(line->find("\"writer_alive\":true"), std::string::npos) << *line;
  ls.signal(SIGINT);
  EXPECT_EQ(ls.wait(), 0) << ls.err();
}

// A FIFO planted at a stream's path (any local user can) must not hold a tool forever: it
// either refuses the path at once or stops on SIGTERM, whatever it waits in.
TEST(EveryTool, StopsOnSigtermWhenAFifoSitsAtTheStreamsPath) {
  const std::string name = unique_name("fifo");
  const std::string path = "/dev/shm/sim." + name.substr(1);
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  for (const std::vector<std::string>& argv :
       {std::vector<std::string>{kEcho, name}, {kLs}, {kRm, "--dead", name}}) {
    Process tool(argv);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    tool.signal(SIGTERM);
    const int code = tool.wait(std::chrono::seconds(10));
    EXPECT_FALSE(tool.deadline_passed()) << argv[0] << " hung on the FIFO";
    EXPECT_TRUE(code == 0 || code == 1) << argv[0] << " exit " << code << ": " << tool.err();
  }
  std::remove(path.c_str());
}

namespace {

// A writer in this process whose stream describes a calibrated camera mounted on the vehicle.
sim::SensorInfo described_camera() {
  sim::SensorInfo sensor;
  sensor.frame_id = "camera_front_optical";
  sensor.parent_frame = "base_link";
  sensor.mounting = sim::Mounting::from_xyz_rpy(1.5, 0, 1.2, 0, 0, 1.5707963);
  sim::CameraCalibration c;
  c.width = 32;
  c.height = 16;
  c.k = {40.5, 0, 16, 0, 41, 8, 0, 0, 1};
  c.p = {40.5, 0, 16, 0, 0, 41, 8, 0, 0, 0, 1, 0};
  c.d = {0.1, 0, 0, 0, 0};
  sensor.calibration = c;
  sensor.identity = {"Acme", "Cam 1", "0815", "2.1"};
  sensor.time_base = sim::TimeBase::host;
  return sensor;
}

Expected<Writer> described_writer(const std::string& name) {
  return Writer::create({.name = name,
                         .layout = Layout::of(ImageLayout::packed(32, 16, PixelFormat::mono8)),
                         .sensor = described_camera()});
}

}  // namespace

TEST(SimLs, ShowsTheFrameParentAndCalibrationSummaryForPeopleAndScripts) {
  StreamGuard g{unique_name("ls_sensor")};
  auto writer = described_writer(g.name);
  ASSERT_TRUE(writer) << writer.error().message;
  const auto table = sim::testing::run({kLs, g.name});
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("sensor: frame camera_front_optical in base_link at x 1.5 y 0 z 1.2 m"),
            std::string::npos)
      << table.out;
  EXPECT_NE(table.out.find(sim::summary(*described_camera().calibration)), std::string::npos)
      << table.out;
  EXPECT_NE(table.out.find("Acme Cam 1 serial 0815"), std::string::npos) << table.out;

  const auto json = sim::testing::run({kLs, "--json", g.name});
  ASSERT_EQ(json.code, 0) << json.err;
  EXPECT_NE(json.out.find("\"frame_id\":\"camera_front_optical\",\"parent_frame\":\"base_link\""),
            std::string::npos)
      << json.out;
  EXPECT_NE(json.out.find("\"translation\":[1.5,0,1.2]"), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"k\":[40.5,0,16,0,41,8,0,0,1]"), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"time_base\":\"host\""), std::string::npos) << json.out;
}

TEST(SimLs, AStreamWithoutADescriptionSaysNothingAndHasANullSensor) {
  StreamGuard g{unique_name("ls_plain")};
  auto writer = start_writer(g.name, 1000000, 50, 0);
  const auto json = sim::testing::run({kLs, "--json", g.name});
  ASSERT_EQ(json.code, 0) << json.err;
  EXPECT_NE(json.out.find("\"sensor\":null"), std::string::npos) << json.out;
  const auto table = sim::testing::run({kLs, g.name});
  EXPECT_EQ(table.out.find("sensor:"), std::string::npos) << table.out;
}

TEST(SimEcho, PrintsTheSensorBeforeTheFirstFrameAndAgainWhenItChanges) {
  StreamGuard g{unique_name("echo_sensor")};
  auto writer = described_writer(g.name);
  ASSERT_TRUE(writer) << writer.error().message;
  Process echo({kEcho, g.name, "--count", "2", "--json"});
  const std::vector<std::byte> frame(32 * 16);
  // sim_echo prints frames published after it opened the stream: publish until it has one.
  std::optional<std::string> first;
  for (int i = 0; i < 3000 && !first; ++i) {
    ASSERT_EQ(writer->write(frame, i + 1), WriteStatus::ok);
    first = echo.next_line(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(first) << echo.err();
  EXPECT_EQ(first->rfind("{\"sensor_generation\":", 0), 0u) << *first;
  EXPECT_NE(first->find("\"frame_id\":\"camera_front_optical\""), std::string::npos) << *first;
  const std::string frame_line = echo.next_line().value_or("");
  EXPECT_NE(frame_line.find("\"seq\":"), std::string::npos) << frame_line;
  // A remount: the next frame comes after a new description.
  sim::SensorInfo moved = described_camera();
  moved.mounting = sim::Mounting::from_xyz_rpy(2.0, 0, 1.2, 0, 0, 0);
  ASSERT_TRUE(writer->set_sensor_info(moved));
  std::optional<std::string> changed;
  for (int i = 0; i < 3000 && !changed; ++i) {
    ASSERT_EQ(writer->write(frame, 100 + i), WriteStatus::ok);
    changed = echo.next_line(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(changed) << echo.err();
  EXPECT_NE(changed->find("\"translation\":[2,0,1.2]"), std::string::npos) << *changed;
  EXPECT_NE(json_number(*changed, "sensor_generation"), json_number(*first, "sensor_generation"));
  EXPECT_EQ(echo.wait(), 0) << echo.err();
}

// ---- each stream's clock (issue 30): sim_ls, sim_ls --clocks, sim_echo ----

namespace {

sim::ClockStatus years_behind_clock() {
  sim::ClockStatus c;
  c.source = sim::ClockSource::replayed;
  c.state = sim::ClockState::unknown;
  c.offset_to_host_ns = -80'000'000'000'000'000;
  c.spread_ns = 900'000;
  c.verdict = sim::ClockVerdict::error;
  c.problem = "the sensor's clock is 2.5 years behind its capture host: it was not synchronised";
  c.stamps = sim::StampClock::sensor;
  return c;
}

sim::ClockStatus good_clock(std::int64_t offset_to_host_ns) {
  sim::ClockStatus c;
  c.source = sim::ClockSource::ptp;
  c.state = sim::ClockState::locked;
  c.grandmaster = "00a069.fffe.0b552d";
  c.offset_to_host_ns = offset_to_host_ns;
  c.spread_ns = 20'000;
  c.verdict = sim::ClockVerdict::ok;
  c.stamps = sim::StampClock::sensor;
  return c;
}

sim::Expected<sim::Writer> clocked_writer(const std::string& name, const sim::ClockStatus& clock) {
  auto writer = sim::Writer::create({.name = name, .capacity = 64});
  if (writer) {
    if (auto set = writer->set_clock(clock); !set) return set.error();
  }
  return writer;
}

// The value of "key" in the first JSON object of `text` that holds `anchor`.
std::string json_line_with(const std::string& text, const std::string& anchor) {
  const auto at = text.find(anchor);
  if (at == std::string::npos) return {};
  const auto begin = text.rfind('\n', at);
  const auto end = text.find('\n', at);
  return text.substr(begin == std::string::npos ? 0 : begin + 1, end - (begin == std::string::npos ? 0 : begin + 1));
}

}  // namespace

TEST(SimLs, ShowsEachStreamsClockWithItsVerdictForPeopleAndScripts) {
  StreamGuard g{unique_name("ls_clock")};
  auto writer = clocked_writer(g.name, years_behind_clock());
  ASSERT_TRUE(writer) << writer.error().message;
  const auto table = sim::testing::run({kLs, g.name});
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("clock: replayed unknown, offset to host -2.5 years ±900 µs: error: the sensor's "
                           "clock is 2.5 years behind"),
            std::string::npos)
      << table.out;
  const auto json = sim::testing::run({kLs, "--json", g.name});
  ASSERT_EQ(json.code, 0) << json.err;
  EXPECT_NE(json.out.find("\"clock\":{\"source\":\"replayed\",\"state\":\"unknown\","
                          "\"offset_to_host_ns\":-80000000000000000,\"verdict\":\"error\","
                          "\"problem\":\"the sensor's clock is 2.5 years behind"),
            std::string::npos)
      << json.out;
}

TEST(SimLs, AStreamWithoutAClockRecordHasAnUnknownClockWithANullOffset) {
  StreamGuard g{unique_name("ls_noclock")};
  auto writer = start_writer(g.name, 1000000, 50, 0);
  const auto json = sim::testing::run({kLs, "--json", g.name});
  ASSERT_EQ(json.code, 0) << json.err;
  EXPECT_NE(json.out.find("\"clock\":{\"source\":\"unknown\",\"state\":\"unknown\",\"offset_to_host_ns\":null,"
                          "\"verdict\":\"unknown\",\"problem\":\"the stream's writer does not report its clock"),
            std::string::npos)
      << json.out;
}

TEST(SimLs, ClocksSaysWhichStreamsPairAndFailsWhenAnyClockIsInError) {
  StreamGuard cam{unique_name("clocks_cam")}, lidar{unique_name("clocks_lidar")}, old{unique_name("clocks_old")};
  auto a = clocked_writer(cam.name, good_clock(1'000'000));
  auto b = clocked_writer(lidar.name, good_clock(-2'000'000));
  ASSERT_TRUE(a && b);
  // No ptp4l here: the socket path names nothing, and --clocks still answers.
  const std::string no_ptp4l = "/tmp/sim_test_no_ptp4l_" + std::to_string(getpid());
  const auto fine = sim::testing::run({kLs, "--clocks", "--ptp4l-socket", no_ptp4l, cam.name, lidar.name});
  EXPECT_EQ(fine.code, 0) << fine.out << fine.err;
  EXPECT_EQ(fine.out.rfind("host: ", 0), 0u) << fine.out;
  EXPECT_NE(fine.out.find(cam.name + " + " + lidar.name + ": yes"), std::string::npos) << fine.out;
  const auto strict = sim::testing::run(
      {kLs, "--clocks", "--tolerance", "1", "--ptp4l-socket", no_ptp4l, cam.name, lidar.name});
  EXPECT_NE(strict.out.find(": no: the clocks of " + cam.name + " and " + lidar.name + " disagree by 3.0 ms"),
            std::string::npos)
      << strict.out;

  auto c = clocked_writer(old.name, years_behind_clock());
  ASSERT_TRUE(c);
  const auto bad = sim::testing::run({kLs, "--clocks", "--json", "--ptp4l-socket", no_ptp4l, cam.name, old.name});
  EXPECT_EQ(bad.code, 1) << "a launch script must be able to refuse to start: " << bad.out;
  const std::string host = json_line_with(bad.out, "{\"host\":");
  EXPECT_NE(host.find("\"source\":"), std::string::npos) << bad.out;
  EXPECT_NE(host.find("\"state\":"), std::string::npos) << host;
  EXPECT_NE(host.find("\"offset_ns\":"), std::string::npos) << host;
  EXPECT_NE(host.find("\"grandmaster\":"), std::string::npos) << host;
  EXPECT_NE(json_line_with(bad.out, "\"name\":\"" + old.name + "\"").find("\"verdict\":\"error\""), std::string::npos)
      << bad.out;
  const std::string pairs = json_line_with(bad.out, "\"pairs\":");
  EXPECT_NE(pairs.find("\"pairable\":false,\"reason\":\"" + old.name + "'s clock is in error"), std::string::npos)
      << pairs;
}

TEST(SimEcho, PrintsTheClockBeforeTheFirstFrameAndAgainWhenItChanges) {
  StreamGuard g{unique_name("echo_clock")};
  auto writer = clocked_writer(g.name, good_clock(5'000));
  ASSERT_TRUE(writer) << writer.error().message;
  Process echo({kEcho, g.name, "--count", "2"});
  const std::vector<std::byte> frame(8);
  std::optional<std::string> first;
  for (int i = 0; i < 3000 && !first; ++i) {
    ASSERT_EQ(writer->write(frame, i + 1), WriteStatus::ok);
    first = echo.next_line(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(first) << echo.err();
  EXPECT_EQ(first->rfind("clock ptp locked", 0), 0u) << *first;
  EXPECT_NE(first->find("offset to host +5 µs ±20 µs: ok"), std::string::npos) << *first;
  EXPECT_TRUE(echo.next_line().value_or("").starts_with("seq ")) << echo.err();
  ASSERT_TRUE(writer->set_clock(years_behind_clock()));
  std::optional<std::string> changed;
  for (int i = 0; i < 3000 && !changed; ++i) {
    ASSERT_EQ(writer->write(frame, 100 + i), WriteStatus::ok);
    changed = echo.next_line(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(changed) << echo.err();
  EXPECT_NE(changed->find(": error: the sensor's clock is 2.5 years behind"), std::string::npos) << *changed;
  EXPECT_EQ(echo.wait(), 0) << echo.err();
}
