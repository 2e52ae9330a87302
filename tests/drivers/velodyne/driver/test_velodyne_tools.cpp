// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap and sim_lidar_velodyne as real processes: the replay publishes exactly the
// decoder's frames; the live driver over UDP publishes the same frames, counts bad datagrams,
// and turns a position packet into the stream's time-sync description, which a replay keeps
// for the recorded stamps and leaves alone with --restamp (this host's clock); it joins a multicast
// group and its source filter drops another sender's packets; a calibration of another laser
// count is one sentence.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "../packet_builder.hpp"
#include "lidar_test/capture_frames.hpp"
#include "lidar_test/pcap_payloads.hpp"
#include "lidar_test/streams.hpp"
#include "sim/sim.hpp"
#include "sim/velodyne/velodyne.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"

namespace {

using namespace std::chrono_literals;
using sim::testing::Process;

std::optional<std::string> g_skip_reason;
const std::string data_dir = VELODYNE_TEST_DATA;
const std::string capture = data_dir + "/vlp16_dual.pcap";
const std::string calibration = data_dir + "/VLP16.yaml";

struct StreamGuard {
  std::string name = "/test_velodyne_tools_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  static inline int counter = 0;
  ~StreamGuard() { (void)sim::destroy(name, true); }
};

long long summary_value(const std::string& text, const std::string& key) {
  const auto at = text.find(" " + key + "=", text.find("summary "));
  if (at == std::string::npos) return -1;
  return std::stoll(text.substr(at + key.size() + 2));
}

std::string summary_text(const std::string& text, const std::string& key) {
  const auto at = text.find(" " + key + "=", text.find("summary "));
  if (at == std::string::npos) return {};
  const auto begin = at + key.size() + 2;
  return text.substr(begin, text.find_first_of(" \n", begin) - begin);
}

// The frames the decoder makes of the capture, each packet's hour from its capture time.
std::vector<std::vector<sim::LidarPoint>> decode_directly(const std::vector<lidar_test::UdpPayload>& payloads) {
  auto loaded = sim::velodyne::Calibration::load(calibration);
  EXPECT_TRUE(loaded);
  auto assembler = sim::velodyne::FrameAssembler::create(std::move(loaded.value()), {});
  EXPECT_TRUE(assembler);
  std::vector<sim::LidarPoint> span(sim::velodyne::frame_capacity(sim::velodyne::Model::vlp16));
  assembler->set_output(span);
  std::vector<std::vector<sim::LidarPoint>> frames;
  for (const auto& p : payloads) {
    const auto r = assembler->push(p.bytes, 0, p.capture_ns);
    if (!r.frame) continue;
    frames.emplace_back(span.begin(), span.begin() + static_cast<std::ptrdiff_t>(r.frame->point_count));
    assembler->set_output(span);
  }
  return frames;
}

using lidar_test::open_when_created;

// The points of the next `count` frames.
std::vector<std::vector<sim::LidarPoint>> receive(sim::Reader& reader, std::size_t count) {
  std::vector<std::vector<sim::LidarPoint>> points;
  for (auto& frame : lidar_test::receive_frames(reader, count)) points.push_back(std::move(frame.points));
  return points;
}

bool same(const std::vector<sim::LidarPoint>& a, const std::vector<sim::LidarPoint>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(sim::LidarPoint)) == 0;
}

void send_to(int port, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  ::close(fd);
}

// Sends the capture's payloads from the loopback address `from` to `to`:`port`, 200 µs apart
// (a pace a loaded machine's receiver keeps up with; the kernel buffer would hold them anyway).
void send_capture(const char* from, const char* to, int port, const std::vector<lidar_test::UdpPayload>& payloads) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  ::inet_pton(AF_INET, from, &local.sin_addr);
  EXPECT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local), 0) << from;
  sockaddr_in destination{};
  destination.sin_family = AF_INET;
  destination.sin_port = htons(static_cast<std::uint16_t>(port));
  ::inet_pton(AF_INET, to, &destination.sin_addr);
  for (const auto& p : payloads) {
    EXPECT_EQ(::sendto(fd, p.bytes.data(), p.bytes.size(), 0, reinterpret_cast<const sockaddr*>(&destination),
                       sizeof destination),
              static_cast<ssize_t>(p.bytes.size()));
    std::this_thread::sleep_for(200us);
  }
  ::close(fd);
}

// sim_lidar_velodyne publishing to a stream of its own with the test calibration, plus the
// `options` of a test (address, ports, filters), and a reader of that stream once start() says
// both are up.
struct LiveDriver {
  StreamGuard stream;
  Process driver;
  int port = -1;           // where it takes data packets
  int position_port = -1;  // and position packets (0 with --no-position)
  std::optional<sim::Reader> reader;

  explicit LiveDriver(const std::vector<std::string>& options) : driver(arguments(stream.name, options)) {}

  static std::vector<std::string> arguments(const std::string& stream, const std::vector<std::string>& options) {
    std::vector<std::string> argv{SIM_LIDAR_VELODYNE, "--model",       "VLP-16",   "--stream",
                                  stream,             "--calibration", calibration, "--summary"};
    argv.insert(argv.end(), options.begin(), options.end());
    return argv;
  }

  // Waits until the driver listens and its stream can be read: "" then, otherwise what failed.
  std::string start() {
    const auto line = driver.wait_for_line("listening on");
    if (!line) return "sim_lidar_velodyne did not listen: " + driver.err();
    // "sim_lidar_velodyne: listening on ADDR:PORT (position packets on port N)"
    port = std::stoi(line->substr(line->rfind(':') + 1));
    position_port = std::stoi(line->substr(line->rfind("port ") + 5));
    if (port <= 0) return "sim_lidar_velodyne listens on no port: " + *line;
    auto opened = open_when_created(stream.name);
    if (!opened) return "cannot read the driver's stream: " + opened.error().message;
    reader.emplace(std::move(*opened));
    return {};
  }

  // Stops it as Ctrl-C does; its exit code.
  int stop() {
    driver.signal(SIGTERM);
    return driver.wait();
  }
};

bool equals_one_of(const std::vector<std::vector<sim::LidarPoint>>& expected, const std::vector<sim::LidarPoint>& frame) {
  for (const auto& e : expected) {
    if (same(e, frame)) return true;
  }
  return false;
}

// The bundled VLP-16 capture (which holds data packets only) with a position packet in front
// (PPS locked, GPRMC valid), as a sensor's two ports record it; a temporary file.
struct CaptureWithPositionPacket {
  std::string path =
      (std::filesystem::temp_directory_path() / ("velodyne_position_" + std::to_string(::getpid()) + ".pcap")).string();
  CaptureWithPositionPacket() {
    namespace pt = sim::pcap::testing;
    const auto frame = [](std::uint16_t port, const pt::Bytes& payload) {
      return pt::ethernet(0x0800, pt::ipv4({192, 168, 1, 201}, {255, 255, 255, 255}, pt::udp(port, port, payload)));
    };
    const auto payloads = lidar_test::read_udp_payloads(capture);
    const auto gprmc = velodyne_test::nmea("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230326,003.1,W");
    std::vector<pt::Record> records{{frame(8308, velodyne_test::position_packet(0, 2, gprmc)),
                                     payloads.front().capture_ns - 1'000'000}};
    for (const auto& p : payloads) records.push_back({frame(2368, p.bytes), p.capture_ns});
    pt::write_capture(path, DLT_EN10MB, records);
  }
  ~CaptureWithPositionPacket() { std::filesystem::remove(path); }
};

// What a replay left in its stream after it ended (the test fails when there is none).
std::optional<sim::SensorInfo> description_of(const std::string& stream) {
  auto reader = sim::Reader::open(stream);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return std::nullopt;
  }
  auto info = reader->sensor_info();
  if (!info) {
    ADD_FAILURE() << info.error().message;
    return std::nullopt;
  }
  return *info;
}

TEST(VelodyneTools, TheLiveDriverJoinsAMulticastGroupAndPublishesWhatIsSentToIt) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto payloads = lidar_test::read_udp_payloads(capture);
  const auto expected = decode_directly(payloads);
  // Bound to every address: only the group membership brings the group's datagrams in.
  LiveDriver live({"--port", "0", "--no-position", "--multicast", "239.201.201.203", "--status-interval", "0"});
  ASSERT_EQ(live.start(), "");
  std::thread feed([&] { send_capture("127.0.0.1", "239.201.201.203", live.port, payloads); });
  const auto frames = receive(*live.reader, 1);
  feed.join();
  ASSERT_EQ(live.stop(), 0) << live.driver.err();
  ASSERT_EQ(frames.size(), 1U) << live.driver.out() << live.driver.err();
  EXPECT_TRUE(equals_one_of(expected, frames[0]));
  EXPECT_EQ(summary_value(live.driver.out(), "malformed"), 0);
  EXPECT_EQ(summary_value(live.driver.out(), "other_source"), 0);
}

TEST(VelodyneTools, TheSourceFilterDropsPacketsOfAnotherSenderAndKeepsTheSensors) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto payloads = lidar_test::read_udp_payloads(capture);
  const auto expected = decode_directly(payloads);
  LiveDriver live({"--bind", "127.0.0.1", "--port", "0", "--no-position", "--source", "127.0.0.2",
                   "--status-interval", "0.05"});
  ASSERT_EQ(live.start(), "");

  // Another sender (127.0.0.1): every datagram counted, none decoded. The status lines (one per
  // tick, in a log) say when the driver has taken them all.
  send_capture("127.0.0.1", "127.0.0.1", live.port, payloads);
  const std::string all_other = "other-source " + std::to_string(payloads.size());
  const auto deadline = std::chrono::steady_clock::now() + 30s;  // a hang guard
  while (live.driver.err().find(all_other) == std::string::npos && std::chrono::steady_clock::now() < deadline) {
    (void)live.driver.next_line(50ms);
  }
  EXPECT_NE(live.driver.err().find(all_other), std::string::npos) << live.driver.err();
  std::vector<std::byte> buffer(live.reader->capacity());
  sim::FrameInfo info;
  EXPECT_NE(live.reader->read_next(buffer, info, 0ms), sim::ReadStatus::new_frame);

  // The sensor (127.0.0.2): decoded as the decoder decodes the capture.
  std::thread feed([&] { send_capture("127.0.0.2", "127.0.0.1", live.port, payloads); });
  const auto frames = receive(*live.reader, 1);
  feed.join();
  ASSERT_EQ(live.stop(), 0) << live.driver.err();
  ASSERT_EQ(frames.size(), 1U) << live.driver.out() << live.driver.err();
  EXPECT_TRUE(equals_one_of(expected, frames[0]));
  EXPECT_EQ(summary_value(live.driver.out(), "other_source"), static_cast<long long>(payloads.size()));
  EXPECT_EQ(summary_value(live.driver.out(), "malformed"), 0);
}

TEST(VelodyneTools, ReplayPublishesExactlyTheDecodersFrames) {
  const auto payloads = lidar_test::read_udp_payloads(capture);
  const auto expected = decode_directly(payloads);
  ASSERT_EQ(expected.size(), 3U);
  StreamGuard stream;
  Process replay({SIM_REPLAY_PCAP, capture, "--stream", stream.name, "--calibration", calibration, "--summary"});
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  const auto frames = receive(*reader, expected.size());
  ASSERT_EQ(replay.wait(), 0) << replay.err();
  ASSERT_EQ(frames.size(), expected.size());
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_TRUE(same(frames[i], expected[i])) << "frame " << i;
  EXPECT_EQ(summary_value(replay.out(), "packets"), 603);
}

TEST(VelodyneTools, LiveDriverCountsBadDatagramsAndReportsThePositionPacketsTimeSync) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const auto payloads = lidar_test::read_udp_payloads(capture);
  const auto expected = decode_directly(payloads);
  LiveDriver live({"--port", "0", "--position-port", "0", "--bind", "127.0.0.1", "--status-interval", "0",
                   "--frame-id", "velodyne_top"});
  ASSERT_EQ(live.start(), "");

  send_to(live.position_port,
          velodyne_test::position_packet(
              0, 2, velodyne_test::nmea("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230326,003.1,W")));
  send_to(live.port, std::vector<std::uint8_t>(payloads[0].bytes.begin(), payloads[0].bytes.begin() + 700));  // cut short
  send_to(live.port, std::vector<std::uint8_t>(1080, 0xEE));  // another vendor's datagram
  std::thread feed([&] {
    for (const auto& p : payloads) {
      send_to(live.port, p.bytes);
      std::this_thread::sleep_for(200us);
    }
  });
  const auto frames = receive(*live.reader, 2);
  feed.join();
  std::this_thread::sleep_for(200ms);
  auto info = live.reader->sensor_info();
  ASSERT_EQ(live.stop(), 0) << live.driver.err();
  // The live stamps' hour comes from the host clock, so the points are compared (their times
  // are offsets from the frame stamp): the live driver's frames are the decoder's.
  ASSERT_GE(frames.size(), 1U);
  EXPECT_TRUE(equals_one_of(expected, frames.back()));
  EXPECT_EQ(summary_value(live.driver.out(), "malformed"), 2);
  EXPECT_EQ(summary_value(live.driver.out(), "position_packets"), 1);
  EXPECT_EQ(summary_text(live.driver.out(), "time_sync"), "PPS_locked__GPRMC_valid");
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  EXPECT_EQ((*info)->frame_id, "velodyne_top");
  EXPECT_EQ((*info)->time_sync, "PPS locked, GPRMC valid");
  EXPECT_EQ((*info)->time_base, sim::TimeBase::sensor_synchronized);
  EXPECT_EQ((*info)->identity.model, "VLP-16");
  EXPECT_EQ((*info)->point_time, sim::PointTime::after_frame_stamp);
}

// --restamp stamps the frames with this host's clock: the recorded position packets are still
// counted, but the stream does not claim the sensor's synchronised clock for them.
TEST(VelodyneTools, ARestampedReplaySaysItsStampsAreThisHostsClockWhateverThePositionPacketsSay) {
  const CaptureWithPositionPacket recorded;
  StreamGuard stream;
  const auto r = sim::testing::run({SIM_REPLAY_PCAP, recorded.path, "--stream", stream.name, "--calibration",
                                    calibration, "--max-rate", "--restamp", "--summary"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(summary_value(r.out, "position_packets"), 1);
  EXPECT_EQ(summary_text(r.out, "time_sync"), "PPS_locked__GPRMC_valid");  // the status line still shows it
  const auto info = description_of(stream.name);
  ASSERT_TRUE(info.has_value()) << "the stream carries no description";
  EXPECT_EQ(info->time_base, sim::TimeBase::host);
  EXPECT_EQ(info->time_sync, "replayed, restamped to this host's clock");
}

// Without --restamp the stamps are the sensor's clock as recorded: the recorded PPS state tells
// whether it was synchronised, and the description says it is a replay.
TEST(VelodyneTools, AReplayWithTheRecordedStampsSaysSoWithTheRecordedPpsState) {
  const CaptureWithPositionPacket recorded;
  StreamGuard stream;
  const auto r = sim::testing::run({SIM_REPLAY_PCAP, recorded.path, "--stream", stream.name, "--calibration",
                                    calibration, "--max-rate", "--summary"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(summary_value(r.out, "position_packets"), 1);
  const auto info = description_of(stream.name);
  ASSERT_TRUE(info.has_value()) << "the stream carries no description";
  EXPECT_EQ(info->time_base, sim::TimeBase::sensor_synchronized);
  EXPECT_EQ(info->time_sync,
            "replayed with the recorded stamps (the sensor's clock); as recorded: PPS locked, GPRMC valid");
}

// The bundled capture holds no position packet: nothing says whether the sensor was synchronised.
TEST(VelodyneTools, AReplayOfACaptureWithoutPositionPacketsLeavesTheTimeBaseUnknown) {
  StreamGuard stream;
  const auto r = sim::testing::run(
      {SIM_REPLAY_PCAP, capture, "--stream", stream.name, "--calibration", calibration, "--max-rate", "--summary"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(summary_value(r.out, "position_packets"), 0);
  const auto info = description_of(stream.name);
  ASSERT_TRUE(info.has_value()) << "the stream carries no description";
  EXPECT_EQ(info->time_base, sim::TimeBase::unknown);
  EXPECT_EQ(info->time_sync,
            "replayed with the recorded stamps (the sensor's clock); as recorded: no position packet yet");
}

TEST(VelodyneTools, ACalibrationOfAnotherLaserCountIsOneSentenceAndExitOne) {
  StreamGuard stream;
  const auto r = sim::testing::run({SIM_REPLAY_PCAP, capture, "--stream", stream.name, "--calibration",
                                    data_dir + "/VLS128.yaml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "sim_replay_pcap: the calibration has 128 lasers but a VLP-16 has 16; give the file of this "
                   "sensor (--calibration).\n");
}

// An HDL-32E with firmware before 2.2.20 (bytes 1204-1205 zero): the replay names Velodyne and
// says to choose the model, never blames Hesai; with --model HDL-32E it publishes its frames.
TEST(VelodyneTools, AnHdl32eOfFirmwareBefore2_2_20IsReplayedWithItsModelAndOtherwiseToldToGiveIt) {
  namespace pt = sim::pcap::testing;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("velodyne_hdl32_" + std::to_string(::getpid()) + ".pcap")).string();
  std::vector<pt::Record> records;
  for (unsigned k = 0; k < 2000; ++k) {
    velodyne_test::DataPacket p;
    p.product_id = 0;
    p.return_mode = 0;
    p.timestamp_us = static_cast<std::uint32_t>(1'000'000 + k * 553);
    for (unsigned b = 0; b < 12; ++b) {
      p.blocks[b].azimuth = static_cast<std::uint16_t>(((k * 12 + b) * 16) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {static_cast<std::uint16_t>(5000 + l), 10};
    }
    const auto ip = pt::ipv4({192, 168, 1, 201}, {255, 255, 255, 255}, pt::udp(2368, 2368, p.bytes()));
    records.push_back({pt::ethernet(0x0800, ip), 1'700'000'000'000'000'000 + std::int64_t{k} * 553'000});
  }
  pt::write_capture(path, DLT_EN10MB, records);
  const std::string hdl32 = std::string(VELODYNE_CALIBRATION_DIR) + "/HDL32.yaml";
  StreamGuard stream;
  const auto refused = sim::testing::run({SIM_REPLAY_PCAP, path, "--stream", stream.name, "--calibration", hdl32});
  EXPECT_EQ(refused.code, 1);
  EXPECT_EQ(refused.err.find("Hesai"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("HDL-32E with firmware before 2.2.20"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("give --model HDL-32E"), std::string::npos) << refused.err;
  const auto replayed = sim::testing::run({SIM_REPLAY_PCAP, path, "--stream", stream.name, "--calibration", hdl32,
                                           "--model", "HDL-32E", "--max-rate", "--summary", "-q"});
  EXPECT_EQ(replayed.code, 0) << replayed.err;
  EXPECT_GE(summary_value(replayed.out, "frames"), 5) << replayed.out;
  EXPECT_EQ(summary_value(replayed.out, "malformed"), 0) << replayed.out;
  std::filesystem::remove(path);
}

// 300 datagrams of another service before the sensor's: the family is found among the datagrams
// --port chose (and a Velodyne calibration names the family anyway), never blamed on Hesai.
TEST(VelodyneTools, TheFamilyIsDetectedAmongTheDatagramsOfTheGivenPort) {
  namespace pt = sim::pcap::testing;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("velodyne_noise_" + std::to_string(::getpid()) + ".pcap")).string();
  const auto payloads = lidar_test::read_udp_payloads(capture);
  std::vector<pt::Record> records;
  const auto frame = [](std::uint16_t port, const pt::Bytes& payload) {
    return pt::ethernet(0x0800, pt::ipv4({192, 168, 1, 7}, {224, 0, 0, 251}, pt::udp(port, port, payload)));
  };
  for (int i = 0; i < 300; ++i) {
    records.push_back({frame(5353, pt::payload_of(120, static_cast<std::uint8_t>(i))),
                       payloads.front().capture_ns - 1'000'000 + i});
  }
  for (const auto& p : payloads) {
    records.push_back({pt::ethernet(0x0800, pt::ipv4({192, 168, 1, 201}, {255, 255, 255, 255},
                                                     pt::udp(2368, 2368, p.bytes))), p.capture_ns});
  }
  pt::write_capture(path, DLT_EN10MB, records);
  StreamGuard stream;
  const auto r = sim::testing::run({SIM_REPLAY_PCAP, path, "--stream", stream.name, "--calibration", calibration,
                                    "--port", "2368", "--max-rate", "--summary", "-q"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_GE(summary_value(r.out, "frames"), 1) << r.out;
  std::filesystem::remove(path);
}

TEST(VelodyneTools, UsageErrorsExitTwoWithOneSentence) {
  const auto no_calibration = sim::testing::run({SIM_LIDAR_VELODYNE, "--port", "0"});
  EXPECT_EQ(no_calibration.code, 2);
  EXPECT_NE(no_calibration.err.find("no calibration file given"), std::string::npos) << no_calibration.err;
  const auto bad_model = sim::testing::run({SIM_LIDAR_VELODYNE, "--model", "VLP-64", "--calibration", calibration});
  EXPECT_EQ(bad_model.code, 2);
  EXPECT_NE(bad_model.err.find("unknown model 'VLP-64'"), std::string::npos) << bad_model.err;
  const auto bad_source = sim::testing::run({SIM_LIDAR_VELODYNE, "--source", "sensor", "--calibration", calibration});
  EXPECT_EQ(bad_source.code, 2);
  EXPECT_NE(bad_source.err.find("is not an IPv4 address"), std::string::npos) << bad_source.err;
  StreamGuard stream;
  const auto not_velodyne = sim::testing::run(
      {SIM_REPLAY_PCAP, capture, "--model", "HDL-32E", "--stream", stream.name, "--calibration", calibration});
  EXPECT_EQ(not_velodyne.code, 1);
  EXPECT_NE(not_velodyne.err.find("holds VLP-16 packets, not HDL-32E"), std::string::npos) << not_velodyne.err;
}

}  // namespace

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::on);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
