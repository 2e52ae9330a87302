// SPDX-License-Identifier: Apache-2.0
// The real tools in real processes: the live driver fed over loopback UDP and over a
// pseudo-terminal standing in for the serial port, and the serial replay; a sim::Reader checks
// that the published frames are exactly what the decoder makes of the same bytes. The suite runs
// in a private network namespace (its own loopback); the UDP tests skip when it cannot.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#ifdef SIM_REPLAY_PCAP_PATH
#include "lidar_test/capture_frames.hpp"  // libpcap's writer, headers written byte by byte
#endif
#include "sim/clock.hpp"
#include "sim/clock_status.hpp"
#include "sim/reader.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"
#include "unitree_encoder.hpp"
#include "vector_sink.hpp"

namespace {

using namespace unitree_test;
using sim::testing::Process;
using namespace std::chrono_literals;

constexpr auto kTimeout = 20s;  // generous: only a hang makes a test wait this long

// Why the suite is not in its private network namespace (the UDP tests skip), or nothing.
std::optional<std::string> g_no_private_network;
#define SKIP_WITHOUT_PRIVATE_NETWORK() \
  if (g_no_private_network) GTEST_SKIP() << *g_no_private_network

std::string unique_name(const char* what) {
  return sim::testing::unique_name(std::string("unitree_") + what);
}

std::string temp_path(const char* what) {
  return (std::filesystem::temp_directory_path() /
          ("unitree_" + std::to_string(getpid()) + "_" + what + ".bin"))
      .string();
}

Bytes read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> c((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return Bytes(c.begin(), c.end());  // no memcpy: an empty file's data() is null
}

void write_file(const std::string& path, std::span<const std::uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

using sim::testing::StreamGuard;

L2PointSpec l2_packet_spec(std::uint32_t seq) {
  L2PointSpec s;
  s.seq = seq;
  s.stamp_sec = 1000;
  s.stamp_nsec = seq * 4'000'000;
  s.a_axis_dist = 0.03F;
  s.b_axis_dist = 0.007F;
  s.beta_angle = 0.02F;
  s.xi_angle = -0.01F;
  s.angle_min = -0.2F;
  s.angle_increment = 0.01F;
  s.com_horizontal_angle_start = 0.1F * static_cast<float>(seq);
  s.com_horizontal_angle_step = 0.0005F;
  s.time_increment = 1.5e-5F;
  for (std::size_t j = 0; j < 300; ++j) {
    s.ranges[j] = static_cast<std::uint16_t>((j % 7 == 0) ? 0 : 800 + 13 * j + seq);
    s.intensities[j] = static_cast<std::uint8_t>(j + seq);
  }
  return s;
}

L2ImuSpec imu_spec() {
  L2ImuSpec s;
  s.seq = 5;
  s.quaternion_wxyz = {0.9238795F, 0.0F, 0.0F, 0.38268343F};
  s.angular_velocity = {0.1F, -0.2F, 0.3F};
  s.linear_acceleration = {0.05F, 0.0F, 9.81F};
  return s;
}

// What the library makes of `bytes`: the reference the published frames must equal.
std::vector<Scan> expected_scans(sim::unitree::Model model, std::uint32_t scan_packets,
                                 std::span<const std::uint8_t> bytes) {
  sim::unitree::DecoderOptions options;
  options.model = model;
  options.packets_per_scan = scan_packets;
  VectorSink sink(sim::unitree::Decoder::max_points_per_scan(options));
  sim::unitree::Decoder decoder(options, sink);
  decoder.push(bytes, 0);
  return sink.scans;
}

// Reads the next frame of `reader` and checks it holds exactly `scan`'s points.
void expect_frame(sim::Reader& reader, const Scan& scan, std::uint64_t seq) {
  std::vector<std::byte> buffer(reader.capacity());
  sim::FrameInfo info;
  ASSERT_EQ(reader.read_next(buffer, info, kTimeout), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.seq, seq);
  ASSERT_EQ(info.size, scan.points.size() * sizeof(sim::LidarPoint));
  EXPECT_EQ(0, std::memcmp(buffer.data(), scan.points.data(), info.size));
  EXPECT_GT(info.stamp_ns, 0);  // host receive time
  // When the scan's first packet reached the host (a replay re-stamps frames later).
  EXPECT_GT(info.receive_ns, 0);
  EXPECT_LE(info.receive_ns, info.stamp_ns);
}

std::optional<sim::Reader> open_reader(const std::string& name) {
  auto reader = sim::Reader::open(name);
  if (!reader) {
    ADD_FAILURE() << "cannot open " << name << ": " << reader.error().message;
    return std::nullopt;
  }
  return std::move(reader.value());
}

// The stream's clock record, once the writer has judged one (about a second after its first
// packet; the record before it only names the stamps' clock); nullopt when none came within the
// generous bound.
std::optional<sim::ClockStatus> wait_for_clock(const sim::Reader& reader) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (std::chrono::steady_clock::now() < deadline) {
    auto clock = reader.clock();
    if (!clock) {
      ADD_FAILURE() << clock.error().message;
      return std::nullopt;
    }
    if (*clock && (*clock)->packets_measured > 0) return **clock;
    std::this_thread::sleep_for(20ms);
  }
  return std::nullopt;
}

// Host-time stamps: the record says so, and finds nothing wrong with them.
void expect_host_time_clock(const sim::Reader& reader) {
  const auto clock = wait_for_clock(reader);
  ASSERT_TRUE(clock) << "no clock record";
  EXPECT_EQ(clock->source, sim::ClockSource::host);
  EXPECT_EQ(clock->stamps, sim::StampClock::host_arrival);
  EXPECT_EQ(clock->verdict, sim::ClockVerdict::ok) << clock->problem;
  EXPECT_GT(clock->packets_measured, 0U);
}

class UdpSender {
 public:
  // Sends to 127.0.0.1:`port` from `from` (another address of the loopback: another sender).
  explicit UdpSender(std::uint16_t port, const char* from = "127.0.0.1") : fd_(socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in local{};
    local.sin_family = AF_INET;
    inet_pton(AF_INET, from, &local.sin_addr);
    EXPECT_EQ(bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof local), 0) << from;
    to_.sin_family = AF_INET;
    to_.sin_port = htons(port);
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~UdpSender() { close(fd_); }
  void send(std::span<const std::uint8_t> datagram) {
    sent.insert(sent.end(), datagram.begin(), datagram.end());
    ASSERT_EQ(sendto(fd_, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&to_),
                     sizeof to_),
              static_cast<ssize_t>(datagram.size()));
  }
  Bytes sent;

 private:
  int fd_;
  sockaddr_in to_{};
};

TEST(UnitreeDriver, L2OverLoopbackUdp) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  StreamGuard guard;
  const std::string stream = unique_name("udp");
  const std::string record = temp_path("udp_record");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0",
                  "--bind-address", "127.0.0.1", "--lidar-ip", "127.0.0.1", "--stream",
                  stream, "--scan-packets", "3", "--record", record, "--summary", "-q"});
  const auto line = driver.next_line(kTimeout);
  ASSERT_TRUE(line.has_value());
  unsigned port = 0;
  ASSERT_EQ(std::sscanf(line->c_str(), "listening on udp port %u", &port), 1) << *line;

  auto points = open_reader(stream);
  auto imu = open_reader(stream + ".imu");
  ASSERT_TRUE(points && imu);
  // 3 packets of 300 points, but at least one 2D-mode packet (1,800 points).
  ASSERT_EQ(points->layout().points.max_points, 1800U);

  UdpSender sender(static_cast<std::uint16_t>(port));
  std::vector<Bytes> packets;
  for (std::uint32_t i = 0; i < 6; ++i) packets.push_back(l2_point_packet(l2_packet_spec(i)));
  Bytes bad = l2_point_packet(l2_packet_spec(99));
  bad[200] ^= std::uint8_t{0xFF};

  // Scan 1: a packet and a half in one datagram, the rest with an IMU packet in the next,
  // then a RoboSense packet, a packet with a bad CRC, and the scan's last packet.
  const std::span<const std::uint8_t> p1(packets[1]);
  sender.send(concat({packets[0], p1.first(500)}));
  sender.send(concat({p1.subspan(500), l2_imu_packet(imu_spec())}));
  sender.send(robosense_packet());
  sender.send(bad);
  sender.send(packets[2]);
  const auto expected = expected_scans(
      sim::unitree::Model::l2, 3,
      concat({packets[0], packets[1], packets[2], packets[3], packets[4], packets[5]}));
  ASSERT_EQ(expected.size(), 2U);
  expect_frame(*points, expected[0], 1);

  std::vector<std::byte> imu_buffer(imu->capacity());
  sim::FrameInfo imu_info;
  ASSERT_EQ(imu->read_next(imu_buffer, imu_info, kTimeout), sim::ReadStatus::new_frame);
  ASSERT_EQ(imu_info.size, sizeof(sim::unitree::ImuSample));
  sim::unitree::ImuSample sample;
  std::memcpy(&sample, imu_buffer.data(), sizeof sample);
  EXPECT_EQ(sample.seq, 5U);
  EXPECT_EQ(sample.quaternion[2], 0.38268343F);  // z of (x, y, z, w)
  EXPECT_EQ(sample.quaternion[3], 0.9238795F);
  EXPECT_EQ(sample.linear_acceleration[2], 9.81F);

  // Scan 2: three packets merged into one datagram.
  sender.send(concat({packets[3], packets[4], packets[5]}));
  expect_frame(*points, expected[1], 2);
  // Host-time stamps (no --sensor-time): written on the driver's once-a-second tick.
  expect_host_time_clock(*points);
  expect_host_time_clock(*imu);

  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0);
  EXPECT_EQ(read_file(record), sender.sent);  // exactly what came off the wire
  // The counters scripts parse, as every LiDAR family begins them: seven packets passed their
  // checksum (six point packets and the IMU's), one did not.
  EXPECT_NE(driver.unread().find("summary frames=2 packets=7 lost=0 malformed=0 imu=1 failed=0 "), std::string::npos)
      << driver.unread();
  EXPECT_NE(driver.unread().find(" bad_crc=1 "), std::string::npos) << driver.unread();
  std::filesystem::remove(record);
}

// --sensor-time live: each packet's L2 time against its arrival on this host. Stamps an hour
// behind the host's clock are found and said, on both streams.
TEST(UnitreeDriver, SensorTimeIsMeasuredAgainstTheArrival) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  StreamGuard guard;
  const std::string stream = unique_name("sensortime");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", "--bind-address",
                  "127.0.0.1", "--stream", stream, "--scan-packets", "3", "--sensor-time", "-q"});
  const auto line = driver.next_line(kTimeout);
  ASSERT_TRUE(line.has_value()) << driver.err();
  unsigned port = 0;
  ASSERT_EQ(std::sscanf(line->c_str(), "listening on udp port %u", &port), 1) << *line;
  auto points = open_reader(stream);
  auto imu = open_reader(stream + ".imu");
  ASSERT_TRUE(points && imu);

  constexpr std::int64_t kHourNs = 3600LL * 1'000'000'000;
  UdpSender sender(static_cast<std::uint16_t>(port));
  for (std::uint32_t i = 0; i < 6; ++i) {
    const std::int64_t sensor = sim::realtime_ns() - kHourNs;
    L2PointSpec spec = l2_packet_spec(i);
    spec.stamp_sec = static_cast<std::uint32_t>(sensor / 1'000'000'000);
    spec.stamp_nsec = static_cast<std::uint32_t>(sensor % 1'000'000'000);
    L2ImuSpec imu_packet = imu_spec();
    imu_packet.stamp_sec = spec.stamp_sec;
    imu_packet.stamp_nsec = spec.stamp_nsec;
    sender.send(concat({l2_point_packet(spec), l2_imu_packet(imu_packet)}));
  }
  for (const sim::Reader* reader : {&*points, &*imu}) {
    const auto clock = wait_for_clock(*reader);
    ASSERT_TRUE(clock) << "no clock record";
    EXPECT_EQ(clock->stamps, sim::StampClock::sensor);
    EXPECT_NE(clock->source, sim::ClockSource::host);
    ASSERT_TRUE(clock->offset_to_host_ns);
    // An hour behind, give or take the time a datagram takes over loopback on a busy machine.
    EXPECT_NEAR(static_cast<double>(*clock->offset_to_host_ns), static_cast<double>(-kHourNs), 1e9);
    EXPECT_EQ(clock->verdict, sim::ClockVerdict::error);
    EXPECT_NE(clock->problem.find("1 h behind"), std::string::npos) << clock->problem;
  }
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0) << driver.err();
}

// A pseudo-terminal pair stands in for the serial port: the driver opens the slave side by name.
struct Pty {
  int master = -1;
  int slave = -1;
  std::string path;
  Pty() {
    if (openpty(&master, &slave, nullptr, nullptr, nullptr) != 0) return;
    // Not inherited by the driver: closing the master must leave its side without one.
    fcntl(master, F_SETFD, FD_CLOEXEC);
    fcntl(slave, F_SETFD, FD_CLOEXEC);
    termios t{};
    tcgetattr(slave, &t);
    cfmakeraw(&t);
    tcsetattr(slave, TCSANOW, &t);
    path = ttyname(slave);
  }
  ~Pty() {
    if (master >= 0) close(master);
    if (slave >= 0) close(slave);
  }
  // Writes in small pieces, so frames arrive cut at arbitrary places.
  void write_in_pieces(std::span<const std::uint8_t> bytes, std::size_t piece) {
    for (std::size_t off = 0; off < bytes.size(); off += piece) {
      const std::size_t n = std::min(piece, bytes.size() - off);
      ASSERT_EQ(::write(master, bytes.data() + off, n), static_cast<ssize_t>(n));
    }
  }
};

void run_serial_driver(sim::unitree::Model model, const Bytes& wire, std::size_t expected_scans_n,
                       const char* baud_text) {
  Pty pty;
  ASSERT_FALSE(pty.path.empty());
  StreamGuard guard;
  const std::string stream = unique_name("serial");
  const std::string record = temp_path(model == sim::unitree::Model::l1 ? "l1_rec" : "l2_rec");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", sim::unitree::to_string(model),
                  "--serial", pty.path, "--stream", stream, "--scan-packets", "2",
                  "--record", record, "-q"});
  const auto line = driver.next_line(kTimeout);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find(baud_text), std::string::npos) << *line;
  auto points = open_reader(stream);
  ASSERT_TRUE(points);

  const auto expected = expected_scans(model, 2, wire);
  ASSERT_EQ(expected.size(), expected_scans_n);
  pty.write_in_pieces(wire, 7);
  // Frames may replace each other before the reader looks; the newest must be the last scan.
  std::vector<std::byte> buffer(points->capacity());
  sim::FrameInfo info;
  std::uint64_t seen = 0;
  while (seen < expected.size()) {
    ASSERT_EQ(points->read_next(buffer, info, kTimeout), sim::ReadStatus::new_frame);
    seen = info.seq;
  }
  const Scan& last = expected.back();
  ASSERT_EQ(info.size, last.points.size() * sizeof(sim::LidarPoint));
  EXPECT_EQ(0, std::memcmp(buffer.data(), last.points.data(), info.size));

  driver.signal(SIGINT);
  EXPECT_EQ(driver.wait(kTimeout), 0);
  EXPECT_EQ(read_file(record), wire);
  std::filesystem::remove(record);
}

Bytes l1_wire() {
  Bytes wire;
  for (std::uint16_t id = 1; id <= 4; ++id) {
    std::array<std::uint16_t, 120> ranges{};
    for (std::size_t j = 0; j < 100; ++j) ranges[j] = static_cast<std::uint16_t>(900 + 11 * j + id);
    L1AuxSpec aux;
    aux.packet_id = id;
    aux.com_horizontal_angle_start = 3.0F * id;
    aux.com_horizontal_angle_step = 3.0F;
    aux.sys_vertical_angle_start = -10.0F;
    aux.sys_vertical_angle_span = 0.5F;
    aux.b_axis_dist = 12.0F;
    aux.theta_angle = 0.01F;
    aux.ksi_angle = 0.02F;
    for (std::size_t j = 0; j < 120; ++j) aux.reflect[j] = static_cast<std::uint8_t>(j * 2);
    wire = concat({wire, l1_distance_frame(id, ranges, static_cast<std::uint8_t>(2 * id)),
                   l1_auxiliary_frame(aux, static_cast<std::uint8_t>(2 * id + 1)),
                   l1_imu_frame({0, 0, 0, 1}, {0.01F, 0, 0}, {0, 0, 9.8F}, id)});
  }
  return wire;
}

TEST(UnitreeDriver, L1OverPseudoTerminal) {
  run_serial_driver(sim::unitree::Model::l1, l1_wire(), 2, "2000000 baud");
}

TEST(UnitreeDriver, L2OverPseudoTerminal) {
  Bytes wire;
  for (std::uint32_t i = 0; i < 4; ++i) {
    wire = concat({wire, l2_point_packet(l2_packet_spec(i)), l2_imu_packet(imu_spec())});
  }
  run_serial_driver(sim::unitree::Model::l2, wire, 2, "4000000 baud");
}

TEST(UnitreeDriver, L1BehindSerialToUdpBoard) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  // The L1's adapter board forwards the MAVLink byte stream over UDP in arbitrary pieces.
  StreamGuard guard;
  const std::string stream = unique_name("l1udp");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L1", "--udp-port", "0",
                  "--bind-address", "127.0.0.1", "--stream", stream, "--scan-packets", "4",
                  "-q"});
  const auto line = driver.next_line(kTimeout);
  ASSERT_TRUE(line.has_value());
  unsigned port = 0;
  ASSERT_EQ(std::sscanf(line->c_str(), "listening on udp port %u", &port), 1) << *line;
  auto points = open_reader(stream);
  ASSERT_TRUE(points);

  const Bytes wire = l1_wire();
  UdpSender sender(static_cast<std::uint16_t>(port));
  for (std::size_t off = 0; off < wire.size(); off += 100) {
    sender.send(std::span<const std::uint8_t>(wire).subspan(off, std::min<std::size_t>(100, wire.size() - off)));
  }
  const auto expected = expected_scans(sim::unitree::Model::l1, 4, wire);
  ASSERT_EQ(expected.size(), 1U);
  expect_frame(*points, expected[0], 1);
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0);
}

TEST(UnitreeDriver, PortInUseIsARuntimeFailure) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  StreamGuard guard;
  const std::string first = unique_name("port1");
  const std::string second = unique_name("port2");
  guard.names = {first, first + ".imu", second, second + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0",
                  "--bind-address", "127.0.0.1", "--stream", first, "-q"});
  const auto line = driver.next_line(kTimeout);
  ASSERT_TRUE(line.has_value());
  unsigned port = 0;
  ASSERT_EQ(std::sscanf(line->c_str(), "listening on udp port %u", &port), 1) << *line;
  Process other({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", std::to_string(port),
                 "--bind-address", "127.0.0.1", "--stream", second, "-q"});
  EXPECT_EQ(other.wait(kTimeout), 1);
  EXPECT_FALSE(sim::inspect(second).has_value());  // a failed start leaves no stream behind
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0);
}

// The port the driver printed, or 0.
unsigned listening_port(Process& driver) {
  const auto line = driver.next_line(kTimeout);
  unsigned port = 0;
  if (!line || std::sscanf(line->c_str(), "listening on udp port %u", &port) != 1) {
    ADD_FAILURE() << "no port line: " << line.value_or("") << driver.err();
  }
  return port;
}

// The packets of one scan of --scan-packets 3, as one datagram each.
std::vector<Bytes> scan_packets(std::uint32_t first) {
  std::vector<Bytes> packets;
  for (std::uint32_t i = first; i < first + 3; ++i) packets.push_back(l2_point_packet(l2_packet_spec(i)));
  return packets;
}

// sim_lidar_unitree for an L2 with 3-packet scans on a free loopback UDP port (`extra`: more
// options), with a reader of its points; its streams are removed at the end.
struct L2OverLoopback {
  explicit L2OverLoopback(const char* what, const std::vector<std::string>& extra = {})
      : stream(unique_name(what)), driver(command(stream, extra)) {
    guard.names = {stream, stream + ".imu"};
    port = static_cast<std::uint16_t>(listening_port(driver));
    if (port != 0) points = open_reader(stream);
  }
  static std::vector<std::string> command(const std::string& stream, const std::vector<std::string>& extra) {
    std::vector<std::string> argv{SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", "--bind-address",
                                  "127.0.0.1", "--stream", stream, "--scan-packets", "3", "--summary", "-q"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return argv;
  }
  // Stops the driver (exit 0 expected) and returns its summary and the rest of its stdout.
  std::string stop() {
    driver.signal(SIGTERM);
    EXPECT_EQ(driver.wait(kTimeout), 0) << driver.err();
    return driver.unread();
  }

  StreamGuard guard;  // first: removes the streams after the driver is gone
  std::string stream;
  Process driver;
  std::uint16_t port = 0;
  std::optional<sim::Reader> points;
};

// The one scan of `packets` (3 L2 packets) is the stream's first frame.
void expect_only_scan(sim::Reader& points, const std::vector<Bytes>& packets) {
  const auto expected = expected_scans(sim::unitree::Model::l2, 3, concat({packets[0], packets[1], packets[2]}));
  ASSERT_EQ(expected.size(), 1U);
  expect_frame(points, expected[0], 1);
}

TEST(UnitreeDriver, DatagramsFromAnotherAddressThanTheLidarIpAreDroppedAndCounted) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  L2OverLoopback d("filtered", {"--lidar-ip", "127.0.0.1"});
  ASSERT_NE(d.port, 0U);
  ASSERT_TRUE(d.points);
  // A whole scan from another sender first: were it taken, it would be the first frame.
  UdpSender stranger(d.port, "127.0.0.2");
  for (const Bytes& packet : scan_packets(10)) stranger.send(packet);
  UdpSender lidar(d.port);
  const std::vector<Bytes> packets = scan_packets(0);
  for (const Bytes& packet : packets) lidar.send(packet);
  expect_only_scan(*d.points, packets);
  const std::string out = d.stop();
  EXPECT_NE(out.find("summary frames=1 packets=3 "), std::string::npos) << out;
  EXPECT_NE(out.find(" other_senders=3\n"), std::string::npos) << out;
}

// Without --lidar-ip every sender is decoded; a second one is two sensors on one port, said
// once with the option that chooses one.
TEST(UnitreeDriver, ASecondSenderWithoutLidarIpIsCountedAndSaidOnce) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  L2OverLoopback d("twosenders");
  ASSERT_NE(d.port, 0U);
  ASSERT_TRUE(d.points);
  UdpSender first(d.port);
  UdpSender second(d.port, "127.0.0.2");
  const std::vector<Bytes> packets = scan_packets(0);
  first.send(packets[0]);
  second.send(packets[1]);
  second.send(packets[2]);
  expect_only_scan(*d.points, packets);
  const std::string out = d.stop();
  EXPECT_NE(out.find(" other_senders=2\n"), std::string::npos) << out;
  const std::string& err = d.driver.err();
  const auto said = err.find("datagrams from 127.0.0.2 arrive besides those from 127.0.0.1");
  ASSERT_NE(said, std::string::npos) << err;
  EXPECT_EQ(err.find("datagrams from", said + 1), std::string::npos) << "said once: " << err;
  EXPECT_NE(err.find("choose one with --lidar-ip."), std::string::npos) << err;
}

// A lidar that falls silent mid-scan and starts again: the half scan from before the silence is
// not mixed into the first scan after it (as for every family; the gap is measured between the
// kernel's arrival stamps, and the test's own pause is the only one near the 0.5 s timeout).
TEST(UnitreeDriver, AScanCutByASilenceIsDroppedNotMixedIntoTheNextOne) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  L2OverLoopback d("silence");
  ASSERT_NE(d.port, 0U);
  ASSERT_TRUE(d.points);
  UdpSender lidar(d.port);
  const std::vector<Bytes> cut = scan_packets(0);
  lidar.send(cut[0]);
  lidar.send(cut[1]);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::vector<Bytes> packets = scan_packets(10);
  for (const Bytes& packet : packets) lidar.send(packet);
  expect_only_scan(*d.points, packets);
  const std::string out = d.stop();
  EXPECT_NE(out.find("summary frames=1 packets=5 "), std::string::npos) << out;
}

// Waits until `path` holds exactly `bytes`; false after the generous bound.
bool file_comes_to_hold(const std::string& path, const Bytes& bytes) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (read_file(path) == bytes) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

// One packet is far less than the recording's buffer: it reaches the file only by the tick,
// which must come while no more bytes do.
TEST(UnitreeDriver, TheRecordingIsFlushedWhileNoMoreDatagramsCome) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  StreamGuard guard;
  const std::string stream = unique_name("udpflush");
  const std::string record = temp_path("udp_flush");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", "--bind-address",
                  "127.0.0.1", "--stream", stream, "--record", record, "-q"});
  const unsigned port = listening_port(driver);
  ASSERT_NE(port, 0U);
  UdpSender sender(static_cast<std::uint16_t>(port));
  sender.send(l2_point_packet(l2_packet_spec(0)));
  EXPECT_TRUE(file_comes_to_hold(record, sender.sent));
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0) << driver.err();
  std::filesystem::remove(record);
}

TEST(UnitreeDriver, TheRecordingIsFlushedWhileTheSerialPortIsQuiet) {
  Pty pty;
  ASSERT_FALSE(pty.path.empty());
  StreamGuard guard;
  const std::string stream = unique_name("serialflush");
  const std::string record = temp_path("serial_flush");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--serial", pty.path, "--stream", stream,
                  "--record", record, "-q"});
  ASSERT_TRUE(driver.next_line(kTimeout).has_value()) << driver.err();
  const Bytes packet = l2_point_packet(l2_packet_spec(0));
  pty.write_in_pieces(packet, packet.size());
  EXPECT_TRUE(file_comes_to_hold(record, packet));
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0) << driver.err();
  std::filesystem::remove(record);
}

// The other end going away (an unplugged adapter) ends the driver with one sentence.
TEST(UnitreeDriver, ASerialPortThatFailsEndsTheDriverWithOneSentence) {
  Pty pty;
  ASSERT_FALSE(pty.path.empty());
  StreamGuard guard;
  const std::string stream = unique_name("unplugged");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L1", "--serial", pty.path, "--stream", stream, "-q"});
  ASSERT_TRUE(driver.next_line(kTimeout).has_value()) << driver.err();
  ::close(pty.master);
  pty.master = -1;
  EXPECT_EQ(driver.wait(kTimeout), 1);
  const std::string& err = driver.err();
  EXPECT_NE(err.find("serial port " + pty.path + " failed ("), std::string::npos) << err;
  EXPECT_NE(err.find("); check the cable and restart\n"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line: " << err;
}

TEST(UnitreeDriver, ABaudRateTheSerialPortHasNoSpeedForIsRefusedInOneSentence) {
  Pty pty;
  ASSERT_FALSE(pty.path.empty());
  const std::string stream = unique_name("badbaud");
  Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L1", "--serial", pty.path, "--baud", "12345",
             "--stream", stream, "-q"});
  EXPECT_EQ(p.wait(kTimeout), 2);
  EXPECT_NE(p.err().find("--baud 12345 is not a rate a serial port can be set to"), std::string::npos) << p.err();
  EXPECT_EQ(p.err().find('\n'), p.err().size() - 1) << "one line: " << p.err();
  EXPECT_FALSE(sim::Reader::open(stream));  // refused before any stream exists
}

TEST(UnitreeDriver, ABadAddressIsRefusedInOneSentenceNamingItsOption) {
  for (const char* option : {"--bind-address", "--lidar-ip"}) {
    const std::string stream = unique_name("badaddress");
    Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", option, "192.168.1", "--stream",
               stream, "-q"});
    EXPECT_EQ(p.wait(kTimeout), 2) << option;
    EXPECT_NE(p.err().find(std::string(option) + ": '192.168.1' is not an IP address"), std::string::npos) << p.err();
    EXPECT_EQ(p.err().find('\n'), p.err().size() - 1) << "one line: " << p.err();
    EXPECT_FALSE(sim::Reader::open(stream));
  }
}

TEST(UnitreeDriver, BadOptionsExitWithUsageOrFailure) {
  {
    Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--stream", "/a/b", "--udp-port", "0", "-q"});
    EXPECT_EQ(p.wait(kTimeout), 2);
  }
  {
    Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L3", "--stream", unique_name("x"), "-q"});
    EXPECT_EQ(p.wait(kTimeout), 2);
  }
  {
    StreamGuard guard;
    const std::string stream = unique_name("nodev");
    guard.names = {stream, stream + ".imu"};
    Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L1", "--serial", "/dev/does-not-exist-unitree",
               "--stream", stream, "-q"});
    EXPECT_EQ(p.wait(kTimeout), 1);
  }
  {
    Process p({SIM_LIDAR_UNITREE_PATH, "--help"});
    EXPECT_EQ(p.wait(kTimeout), 0);
  }
}

TEST(UnitreeReplaySerial, ReplaysARecordingThroughTheSameDecoder) {
  StreamGuard guard;
  const std::string stream = unique_name("replay");
  guard.names = {stream, stream + ".imu"};
  const std::string file = temp_path("replay_input");
  // Two scans of 3 packets with line noise before, between and after.
  const Bytes noise = {std::uint8_t{0x55}, std::uint8_t{0xAA}, std::uint8_t{0x01}, std::uint8_t{0x7E}};
  Bytes wire = noise;
  for (std::uint32_t i = 0; i < 6; ++i) {
    wire = concat({wire, l2_point_packet(l2_packet_spec(i)), (i == 2 ? noise : Bytes{})});
  }
  wire = concat({wire, l2_imu_packet(imu_spec()), noise});
  write_file(file, wire);
  Process replay({SIM_REPLAY_SERIAL_PATH, file, "--model", "L2", "--stream", stream,
                  "--scan-packets", "3", "--rate-hz", "0", "-q"});
  ASSERT_EQ(replay.wait(kTimeout), 0);

  const auto expected = expected_scans(sim::unitree::Model::l2, 3, wire);
  ASSERT_EQ(expected.size(), 2U);
  auto status = sim::inspect(stream);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->frames_published, 2U);
  auto points = open_reader(stream);
  ASSERT_TRUE(points);
  expect_frame(*points, expected[1], 2);  // the newest frame is the second scan
  auto described = points->sensor_info();
  ASSERT_TRUE(described && *described);
  EXPECT_EQ((*described)->time_base, sim::TimeBase::host);
  EXPECT_EQ((*described)->time_sync, "replayed, stamped with this host's clock when published");
  expect_host_time_clock(*points);
  auto imu_status = sim::inspect(stream + ".imu");
  ASSERT_TRUE(imu_status.has_value());
  EXPECT_EQ(imu_status->frames_published, 1U);
  std::filesystem::remove(file);
}

TEST(UnitreeReplaySerial, BadInputIsReportedWithExitCodes) {
  const std::string garbage = temp_path("garbage");
  write_file(garbage, Bytes(5000, std::uint8_t{0x42}));
  StreamGuard guard;
  const std::string stream = unique_name("bad");
  guard.names = {stream, stream + ".imu"};
  {
    Process p({SIM_REPLAY_SERIAL_PATH, garbage, "--model", "L2", "--stream", stream, "-q"});
    EXPECT_EQ(p.wait(kTimeout), 1);
  }
  {
    Process p({SIM_REPLAY_SERIAL_PATH, "/nonexistent/unitree.bin", "--model", "L1",
               "--stream", stream, "-q"});
    EXPECT_EQ(p.wait(kTimeout), 1);
  }
  {
    Process p({SIM_REPLAY_SERIAL_PATH, garbage, "--model", "X9", "--stream", stream, "-q"});
    EXPECT_EQ(p.wait(kTimeout), 2);
  }
  std::filesystem::remove(garbage);
}

#ifdef SIM_REPLAY_PCAP_PATH
// A capture of the L2's UDP stream as tcpdump would write it (raw IP link type): one datagram
// per packet, 4 ms apart.
void write_udp_capture(const std::string& path, const std::vector<Bytes>& payloads) {
  namespace capture = sim::pcap::testing;
  std::vector<capture::Record> records;
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(payloads[i].data());
    const capture::Bytes datagram = capture::udp(6201, 6201, capture::Bytes(bytes, bytes + payloads[i].size()));
    records.push_back({capture::ipv4({192, 168, 1, 62}, {192, 168, 1, 2}, datagram),
                       1'700'000'000'000'000'000 + static_cast<std::int64_t>(i) * 4'000'000, 0});
  }
  capture::write_capture(path, DLT_RAW, records);
}

TEST(UnitreeReplayPcap, PublishesTheScansOfAnL2CaptureAsTheLibraryDecodesThem) {
  StreamGuard guard;
  const std::string stream = unique_name("pcap");
  guard.names = {stream, stream + ".imu"};
  const std::string file = temp_path("capture") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 9; ++i) payloads.push_back(l2_point_packet(l2_packet_spec(i)));
  payloads.push_back(l2_imu_packet(imu_spec()));
  write_udp_capture(file, payloads);
  Bytes wire;
  for (const auto& p : payloads) wire = concat({wire, p});
  const auto expected = expected_scans(sim::unitree::Model::l2, 3, wire);
  ASSERT_EQ(expected.size(), 3U);

  Process replay({SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                  "--scan-packets", "3", "--max-rate", "--summary", "-q"});
  ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
  EXPECT_NE(replay.out().find("summary frames=3 packets=10"), std::string::npos) << replay.out();
  auto status = sim::inspect(stream);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->frames_published, 3U);
  auto points = open_reader(stream);
  ASSERT_TRUE(points);
  expect_frame(*points, expected[2], 3);  // the newest frame is the third scan
  auto imu_status = sim::inspect(stream + ".imu");
  ASSERT_TRUE(imu_status.has_value());
  EXPECT_EQ(imu_status->frames_published, 1U);
  std::filesystem::remove(file);
}

TEST(UnitreeReplayPcap, ALoopingReplayKeepsWholeScansAndIncreasingStamps) {
  StreamGuard guard;
  const std::string stream = unique_name("pcaploop");
  guard.names = {stream, stream + ".imu"};
  const std::string file = temp_path("loop") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 9; ++i) payloads.push_back(l2_point_packet(l2_packet_spec(i)));
  write_udp_capture(file, payloads);
  Process replay({SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                  "--scan-packets", "3", "--rate", "4", "--loop", "--summary", "-q"});
  auto reader = sim::testing::wait_for_stream(stream);
  ASSERT_TRUE(reader) << replay.err();
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  std::int64_t last_stamp = 0;
  // Seven scans is more than two passes of three: stamps increase across the wraps.
  while (info.seq < 7) {
    ASSERT_EQ(reader->read_next(buffer, info, kTimeout), sim::ReadStatus::new_frame);
    EXPECT_GT(info.stamp_ns, last_stamp) << "seq " << info.seq;
    EXPECT_EQ(info.size, expected_scans(sim::unitree::Model::l2, 3,
                                        concat({payloads[0], payloads[1], payloads[2]}))[0]
                                 .points.size() * sizeof(sim::LidarPoint));
    last_stamp = info.stamp_ns;
  }
  replay.signal(SIGINT);
  EXPECT_EQ(replay.wait(kTimeout), 0) << replay.err();
  std::filesystem::remove(file);
}

// Which clock the replayed stamps are, on the point and the IMU stream: this host's with
// --restamp, otherwise the capture's times, the recording host's clock.
TEST(UnitreeReplayPcap, TheStreamsSayWhichClockTheirStampsAreWithAndWithoutRestamp) {
  const std::string file = temp_path("clock") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 3; ++i) payloads.push_back(l2_point_packet(l2_packet_spec(i)));
  payloads.push_back(l2_imu_packet(imu_spec()));
  write_udp_capture(file, payloads);
  struct Case {
    bool restamp;
    std::string time_sync;
  };
  const std::vector<Case> cases = {
      {true, "replayed, restamped to this host's clock"},
      {false, "replayed with the recorded stamps (the recording host's clock when it captured each packet)"},
  };
  for (const Case& expected : cases) {
    StreamGuard guard;
    const std::string stream = unique_name("pcapclock");
    guard.names = {stream, stream + ".imu"};
    std::vector<std::string> argv{SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                                  "--scan-packets", "3", "--max-rate", "-q"};
    if (expected.restamp) argv.push_back("--restamp");
    Process replay(argv);
    ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
    for (const std::string& name : guard.names) {
      auto reader = open_reader(name);
      ASSERT_TRUE(reader) << name;
      auto described = reader->sensor_info();
      ASSERT_TRUE(described && *described) << name;
      EXPECT_EQ((*described)->time_base, sim::TimeBase::host) << name;
      EXPECT_EQ((*described)->time_sync, expected.time_sync) << name << ", restamp " << expected.restamp;
    }
  }
  std::filesystem::remove(file);
}

constexpr std::int64_t kCaptureStartNs = 1'700'000'000LL * 1'000'000'000;  // write_udp_capture's
constexpr std::int64_t kCapturePeriodNs = 4'000'000;

// With --sensor-time the L2's own clock is measured against the capture's time of each record:
// the record's offset is what the test computes from the packets' times and the capture's.
TEST(UnitreeReplayPcap, SensorTimeIsMeasuredAgainstTheCaptureTimes) {
  const std::string file = temp_path("sensorclock") + ".pcap";
  std::vector<Bytes> payloads;
  std::vector<std::int64_t> offsets;  // sensor − capture of each packet
  for (std::uint32_t i = 0; i < 30; ++i) {
    const std::int64_t offset = 2'000'000 + (i % 3) * 100'000;  // 2.0 … 2.2 ms ahead
    const std::int64_t sensor = kCaptureStartNs + i * kCapturePeriodNs + offset;
    offsets.push_back(offset);
    if (i % 10 == 9) {
      L2ImuSpec imu = imu_spec();
      imu.stamp_sec = static_cast<std::uint32_t>(sensor / 1'000'000'000);
      imu.stamp_nsec = static_cast<std::uint32_t>(sensor % 1'000'000'000);
      payloads.push_back(l2_imu_packet(imu));
      continue;
    }
    L2PointSpec spec = l2_packet_spec(i);
    spec.stamp_sec = static_cast<std::uint32_t>(sensor / 1'000'000'000);
    spec.stamp_nsec = static_cast<std::uint32_t>(sensor % 1'000'000'000);
    payloads.push_back(l2_point_packet(spec));
  }
  write_udp_capture(file, payloads);
  std::vector<std::int64_t> sorted = offsets;
  std::sort(sorted.begin(), sorted.end());
  const std::int64_t median = sorted[sorted.size() / 2];

  StreamGuard guard;
  const std::string stream = unique_name("pcapsensor");
  guard.names = {stream, stream + ".imu"};
  Process replay({SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                  "--scan-packets", "3", "--max-rate", "--sensor-time", "-q"});
  ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
  for (const std::string& name : guard.names) {
    auto reader = open_reader(name);
    ASSERT_TRUE(reader) << name;
    const auto clock = wait_for_clock(*reader);
    ASSERT_TRUE(clock) << name << ": no clock record";
    EXPECT_EQ(clock->source, sim::ClockSource::replayed) << name;
    EXPECT_EQ(clock->stamps, sim::StampClock::sensor) << name;
    ASSERT_TRUE(clock->offset_to_host_ns) << name;
    // The check keeps a decimated sample: within the packets' own spread of the median.
    EXPECT_NEAR(static_cast<double>(*clock->offset_to_host_ns), static_cast<double>(median), 100'000.0)
        << name;
    EXPECT_EQ(clock->verdict, sim::ClockVerdict::ok) << name << ": " << clock->problem;
    EXPECT_EQ(clock->packets_measured, payloads.size()) << name;
  }
  // The frames carry the sensor's time (2.0 … 2.2 ms past a capture time), not the capture's.
  auto points = open_reader(stream);
  ASSERT_TRUE(points);
  std::vector<std::byte> buffer(points->capacity());
  sim::FrameInfo info;
  ASSERT_EQ(points->read_next(buffer, info, kTimeout), sim::ReadStatus::new_frame);
  EXPECT_GE((info.stamp_ns - kCaptureStartNs) % kCapturePeriodNs, 2'000'000);
  std::filesystem::remove(file);
}

// --sensor-time --restamp: the L2's times moved to the present, judged as this host's time.
TEST(UnitreeReplayPcap, RestampedSensorTimeIsJudgedAsHostTime) {
  const std::string file = temp_path("restampsensor") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 30; ++i) {
    // The L2 counted from power-on: 1970 stamps, which --restamp moves to the present.
    L2PointSpec spec = l2_packet_spec(i);
    spec.stamp_sec = 100;
    spec.stamp_nsec = i * static_cast<std::uint32_t>(kCapturePeriodNs);
    payloads.push_back(l2_point_packet(spec));
  }
  write_udp_capture(file, payloads);
  StreamGuard guard;
  const std::string stream = unique_name("pcaprestamp");
  guard.names = {stream, stream + ".imu"};
  Process replay({SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                  "--scan-packets", "3", "--sensor-time", "--restamp", "-q"});
  ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
  auto reader = open_reader(stream);
  ASSERT_TRUE(reader);
  const auto clock = wait_for_clock(*reader);
  ASSERT_TRUE(clock);
  EXPECT_EQ(clock->source, sim::ClockSource::host);
  EXPECT_EQ(clock->stamps, sim::StampClock::host_arrival);
  ASSERT_TRUE(clock->offset_to_host_ns);
  // Paced as captured, measured against the present: off by the pacing only, not by 56 years.
  EXPECT_LT(std::abs(*clock->offset_to_host_ns), 1'000'000'000);
  EXPECT_EQ(clock->problem.find("1970"), std::string::npos) << clock->problem;
  std::filesystem::remove(file);
}

// A sensor clock an hour behind the capture: the record says so (an error), in sensor-time mode.
TEST(UnitreeReplayPcap, ASensorClockAnHourOffIsAnError) {
  const std::string file = temp_path("hourclock") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 9; ++i) {
    const std::int64_t sensor = kCaptureStartNs + i * kCapturePeriodNs - 3600LL * 1'000'000'000;
    L2PointSpec spec = l2_packet_spec(i);
    spec.stamp_sec = static_cast<std::uint32_t>(sensor / 1'000'000'000);
    spec.stamp_nsec = static_cast<std::uint32_t>(sensor % 1'000'000'000);
    payloads.push_back(l2_point_packet(spec));
  }
  write_udp_capture(file, payloads);
  StreamGuard guard;
  const std::string stream = unique_name("pcaphour");
  guard.names = {stream, stream + ".imu"};
  Process replay({SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                  "--scan-packets", "3", "--max-rate", "--sensor-time", "-q"});
  ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
  auto reader = open_reader(stream);
  ASSERT_TRUE(reader);
  const auto clock = wait_for_clock(*reader);
  ASSERT_TRUE(clock);
  ASSERT_TRUE(clock->offset_to_host_ns);
  EXPECT_EQ(*clock->offset_to_host_ns, -3600LL * 1'000'000'000);
  EXPECT_EQ(clock->verdict, sim::ClockVerdict::error);
  EXPECT_NE(clock->problem.find("1 h behind"), std::string::npos) << clock->problem;
  std::filesystem::remove(file);
}

// Host-time stamps (the capture's times, or this host's with --restamp): source host, stamps
// host_arrival, nothing wrong with them; on the IMU stream too.
TEST(UnitreeReplayPcap, HostTimeStampsHaveAHostClockRecord) {
  const std::string file = temp_path("hostclock") + ".pcap";
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 9; ++i) payloads.push_back(l2_point_packet(l2_packet_spec(i)));
  payloads.push_back(l2_imu_packet(imu_spec()));
  write_udp_capture(file, payloads);
  for (const bool restamp : {false, true}) {
    StreamGuard guard;
    const std::string stream = unique_name("pcaphost");
    guard.names = {stream, stream + ".imu"};
    std::vector<std::string> argv{SIM_REPLAY_PCAP_PATH, file, "--model", "unitree-l2", "--stream", stream,
                                  "--scan-packets", "3", "-q"};
    if (restamp) argv.push_back("--restamp");
    Process replay(argv);
    ASSERT_EQ(replay.wait(kTimeout), 0) << replay.err();
    for (const std::string& name : guard.names) {
      SCOPED_TRACE(name + (restamp ? " --restamp" : ""));
      auto reader = open_reader(name);
      ASSERT_TRUE(reader);
      expect_host_time_clock(*reader);
      const auto clock = wait_for_clock(*reader);
      ASSERT_TRUE(clock && clock->offset_to_host_ns);
      EXPECT_EQ(*clock->offset_to_host_ns, 0);  // each stamp is its arrival
    }
  }
  std::filesystem::remove(file);
}

TEST(UnitreeReplayPcap, BadArgumentsAreRefusedBeforeAnythingIsOpened) {
  Process bad_stream({SIM_REPLAY_PCAP_PATH, "/nonexistent.pcap", "--model", "unitree-l2",
                      "--stream", "no_slash"});
  EXPECT_EQ(bad_stream.wait(kTimeout), 2);
  EXPECT_NE(bad_stream.err().find("must start with '/'"), std::string::npos) << bad_stream.err();
  Process missing({SIM_REPLAY_PCAP_PATH, "/nonexistent.pcap", "--model", "unitree-l2",
                   "--stream", unique_name("missing")});
  EXPECT_EQ(missing.wait(kTimeout), 1);
  Process help({SIM_REPLAY_PCAP_PATH, "--model", "unitree-l2", "--help"});
  EXPECT_EQ(help.wait(kTimeout), 0);
  EXPECT_NE(help.out().find("--scan-packets"), std::string::npos);
}
#endif

}  // namespace

TEST(UnitreeDriver, TheStreamsCarryTheFrameMountingAndClockGiven) {
  SKIP_WITHOUT_PRIVATE_NETWORK();
  StreamGuard guard;
  const std::string stream = unique_name("described");
  guard.names = {stream, stream + ".imu"};
  Process driver({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", "--bind-address",
                  "127.0.0.1", "--stream", stream, "-q", "--frame-id", "lidar_l2",
                  "--parent-frame", "base_link", "--z", "0.3", "--pitch", "0.2"});
  ASSERT_TRUE(driver.next_line(kTimeout).has_value()) << driver.err();
  auto points = open_reader(stream);
  auto imu = open_reader(stream + ".imu");
  ASSERT_TRUE(points && imu);
  auto info = points->sensor_info();
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  const sim::SensorInfo& s = **info;
  EXPECT_EQ(s.frame_id, "lidar_l2");
  ASSERT_TRUE(s.mounting.has_value());
  EXPECT_EQ(s.mounting->translation[2], 0.3);
  EXPECT_EQ(s.mounting->rotation, sim::Mounting::from_xyz_rpy(0, 0, 0.3, 0, 0.2, 0).rotation);
  EXPECT_EQ(s.identity.vendor, "Unitree");
  EXPECT_EQ(s.identity.model, "L2");
  EXPECT_EQ(s.point_time, sim::PointTime::after_frame_stamp);
  EXPECT_EQ(s.time_base, sim::TimeBase::host);
  auto imu_info = imu->sensor_info();
  ASSERT_TRUE(imu_info) << imu_info.error().message;
  ASSERT_TRUE(imu_info->has_value());
  EXPECT_EQ((*imu_info)->frame_id, "lidar_l2");
  EXPECT_EQ((*imu_info)->point_time, sim::PointTime::none);
  driver.signal(SIGTERM);
  EXPECT_EQ(driver.wait(kTimeout), 0) << driver.err();
}

TEST(UnitreeDriver, ABadFrameNameIsExitTwoBeforeAnythingIsOpened) {
  const std::string stream = unique_name("badframe");
  Process p({SIM_LIDAR_UNITREE_PATH, "--model", "L2", "--udp-port", "0", "--stream", stream,
             "-q", "--frame-id", "lidar l2"});
  EXPECT_EQ(p.wait(kTimeout), 2) << p.err();
  EXPECT_EQ(p.err().find('\n'), p.err().size() - 1) << "one line: " << p.err();
  EXPECT_FALSE(sim::Reader::open(stream));
}

int main(int argc, char** argv) {
  g_no_private_network = sim::testing::enter_private_network(sim::testing::Multicast::off);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
