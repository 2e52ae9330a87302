// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap and sim_lidar_hesai as real processes: a reader in this process must receive
// every revolution, in order, byte for byte what the decoder gives for the capture; the live
// driver fed the capture's payloads over UDP on loopback must publish the same frames; bad
// input must end in one clear sentence and the documented exit code.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "lidar_test/capture_frames.hpp"
#include "lidar_test/streams.hpp"
#include "sim/hesai/hesai.hpp"
#include "sim/pcap/capture.hpp"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// The value of `key=` in the tools' final "summary key=value …" line, or -1.
long long summary_value(const std::string& text, const std::string& key) {
  const auto line = text.find("summary ");
  if (line == std::string::npos) return -1;
  const auto at = text.find(" " + key + "=", line);
  if (at == std::string::npos) return -1;
  return std::stoll(text.substr(at + key.size() + 2));
}
using sim::testing::Process;
using sim::testing::run;

const fs::path data_dir = SIM_HESAI_TEST_DATA;
const std::string replay_tool = SIM_REPLAY_PCAP;
const std::string live_tool = SIM_LIDAR_HESAI;
const std::string p64_capture = (data_dir / "pandar64_dual.pcap").string();
const std::string p64_calibration = (data_dir / "pandar64.calibration.csv").string();

std::string unique_stream() {
  static int counter = 0;
  return "/test_hesai_drv_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

// Removes the stream when the test ends, however it ends.
struct StreamGuard {
  std::string name = unique_stream();
  ~StreamGuard() { (void)sim::destroy(name, true); }
};

using Frame = lidar_test::ReceivedFrame;
using lidar_test::open_when_created;
using lidar_test::receive_frames;

bool same_points(const std::vector<sim::LidarPoint>& a, const std::vector<sim::LidarPoint>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(sim::LidarPoint)) == 0);
}

struct Payload {
  std::vector<std::uint8_t> bytes;
  std::int64_t timestamp_ns;
};

std::vector<Payload> payloads_of(const std::string& path) {
  auto reader = sim::pcap::CaptureReader::open(path);
  EXPECT_TRUE(reader) << reader.error().message;
  std::vector<Payload> out;
  sim::pcap::Datagram d;
  while (reader && reader->next(d) == sim::pcap::NextStatus::datagram) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(d.payload.data());
    out.push_back({{p, p + d.payload.size()}, d.timestamp_ns});
  }
  return out;
}

// What the decoder library itself makes of the payloads, with the tools' default settings.
std::vector<Frame> decode_directly(const std::vector<Payload>& payloads, sim::hesai::Model model,
                                   const std::string& calibration_path) {
  auto calibration = sim::hesai::Calibration::load(calibration_path, model);
  EXPECT_TRUE(calibration);
  sim::hesai::AssemblerOptions options;
  options.model = model;
  auto assembler = sim::hesai::FrameAssembler::create(std::move(calibration.value()), options);
  EXPECT_TRUE(assembler);
  std::vector<sim::LidarPoint> out(sim::hesai::frame_capacity(model));
  assembler->set_output(out);
  std::vector<Frame> frames;
  for (const Payload& p : payloads) {
    const auto result = assembler->push(p.bytes, 0);
    if (result.frame) {
      frames.push_back({{out.begin(), out.begin() + static_cast<std::ptrdiff_t>(result.frame->point_count)},
                        result.frame->stamp_ns, 0});
      assembler->set_output(out);
    }
  }
  return frames;
}

void expect_same_frames(const std::vector<Frame>& got, const std::vector<Frame>& expected,
                        std::uint64_t first_seq) {
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].seq, first_seq + i) << "frame " << i << " missing or out of order";
    EXPECT_EQ(got[i].stamp_ns, expected[i].stamp_ns) << "frame " << i;
    EXPECT_EQ(got[i].points.size(), expected[i].points.size()) << "frame " << i;
    EXPECT_TRUE(same_points(got[i].points, expected[i].points)) << "frame " << i;
  }
}

// ---- replay -----------------------------------------------------------------------------------

TEST(ReplayTool, ReaderInAnotherProcessGetsEveryRevolutionInOrder) {
  const auto payloads = payloads_of(p64_capture);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);
  // 0.4 s of a 10 Hz sensor: whole revolutions between partial ones at both ends.
  ASSERT_GE(expected.size(), 2u);

  StreamGuard stream;
  // Paced at half speed: one revolution every 200 ms leaves the reader ample time per frame, so
  // "every frame" tests the replay, not the scheduler.
  Process replay({replay_tool, p64_capture, "--stream", stream.name, "--calibration",
                  p64_calibration, "--rate", "0.5", "--summary"});
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ(reader->layout().points.type, sim::PointType::lidar_point);
  const auto frames = receive_frames(*reader, expected.size());
  ASSERT_EQ(replay.wait(), 0) << replay.err();
  expect_same_frames(frames, expected, 1);
  EXPECT_EQ(summary_value(replay.out(), "frames"), static_cast<long long>(expected.size()));
  EXPECT_EQ(summary_value(replay.out(), "packets"), 2400);
  EXPECT_EQ(summary_value(replay.out(), "lost"), 0);
  EXPECT_EQ(summary_value(replay.out(), "malformed"), 0);
}

TEST(ReplayTool, MaxRateAndRawEthernetPandar40P) {
  const std::string capture = (data_dir / "pandar40p_last_20hz_raw.pcapng").string();
  const std::string calibration = (data_dir / "pandar40p.example-calibration.csv").string();
  const auto expected =
      decode_directly(payloads_of(capture), sim::hesai::Model::pandar40p, calibration);
  ASSERT_FALSE(expected.empty());
  StreamGuard stream;
  const auto result = run({replay_tool, capture, "--stream", stream.name, "--calibration",
                           calibration, "--max-rate", "--summary", "--port", "2369"});
  ASSERT_EQ(result.code, 0) << result.err;
  EXPECT_EQ(summary_value(result.out, "frames"), static_cast<long long>(expected.size()));
  EXPECT_EQ(summary_value(result.out, "packets"), 200);
  EXPECT_EQ(summary_value(result.out, "lost"), 0);
  // The newest frame stays in the region after the replay ends.
  auto reader = sim::Reader::open(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.seq, expected.size());
  EXPECT_EQ(info.size, expected.back().points.size() * sizeof(sim::LidarPoint));
  EXPECT_EQ(info.stamp_ns, expected.back().stamp_ns);
  // A whole revolution of a 20 Hz sensor: its firings span about 50 ms (a 10 Hz one, 100 ms).
  std::uint32_t last_firing = 0;
  for (std::size_t i = 0; i < info.size / sizeof(sim::LidarPoint); ++i) {
    sim::LidarPoint p;
    std::memcpy(&p, buffer.data() + i * sizeof p, sizeof p);
    last_firing = std::max(last_firing, p.time_offset_ns);
  }
  EXPECT_GT(last_firing, 45'000'000u);
  EXPECT_LT(last_firing, 55'000'000u);
}

TEST(ReplayTool, SameFramesThroughEveryEncapsulation) {
  // The Pandar64 payloads rewrapped as a trunk port (QinQ, IPv4 options) and as "tcpdump -i any"
  // (SLL2) would record them: the replay must publish the same revolutions as from the original.
  using namespace sim::pcap::testing;
  const auto payloads = payloads_of(p64_capture);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);
  const fs::path dir = fs::temp_directory_path() / ("sim_replay_encap_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<Record> trunk, any;
  for (const Payload& p : payloads) {
    const Bytes datagram = udp(10000, 2368, p.bytes);
    trunk.push_back({ethernet(0x0800, ipv4({192, 168, 1, 201}, {192, 168, 1, 100}, datagram, 17,
                                           {0x94, 0x04, 0x00, 0x00}),
                              {{0x88a8, 0x0010}, {0x8100, 0x0064}}),
                     p.timestamp_ns});
    any.push_back({sll2(0x0800, ipv4({192, 168, 1, 201}, {192, 168, 1, 100}, datagram)), p.timestamp_ns});
    // Other traffic on the wire: the filter or the parser must drop it.
    trunk.push_back({ethernet(0x0800, ipv4({192, 168, 1, 201}, {192, 168, 1, 100}, udp(10000, 10110, Bytes(512, 0))),
                              {{0x8100, 0x0064}}),
                     p.timestamp_ns});
  }
  write_capture((dir / "trunk.pcap").string(), DLT_EN10MB, trunk, true);
  write_capture((dir / "any.pcap").string(), DLT_LINUX_SLL2, any);
  for (const std::string name : {"trunk.pcap", "any.pcap"}) {
    StreamGuard stream;
    const auto result = run({replay_tool, (dir / name).string(), "--stream", stream.name,
                             "--calibration", p64_calibration, "--max-rate", "--port", "2368",
                             "--summary"});
    ASSERT_EQ(result.code, 0) << name << ": " << result.err;
    EXPECT_EQ(summary_value(result.out, "frames"), static_cast<long long>(expected.size())) << name;
    EXPECT_EQ(summary_value(result.out, "packets"), 2400) << name;
    EXPECT_EQ(summary_value(result.out, "malformed"), 0) << name;
    auto reader = sim::Reader::open(stream.name);
    ASSERT_TRUE(reader);
    std::vector<std::byte> buffer(reader->capacity());
    sim::FrameInfo info;
    ASSERT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
    EXPECT_EQ(info.stamp_ns, expected.back().stamp_ns) << name;
    ASSERT_EQ(info.size, expected.back().points.size() * sizeof(sim::LidarPoint)) << name;
    EXPECT_EQ(std::memcmp(buffer.data(), expected.back().points.data(), info.size), 0) << name;
  }
  fs::remove_all(dir);
}

TEST(ReplayTool, LoopStartAndDuration) {
  StreamGuard stream;
  // Passes of the whole capture at full speed: each pass publishes the same revolutions.
  Process looping({replay_tool, p64_capture, "--stream", stream.name, "--calibration",
                   p64_calibration, "--max-rate", "--loop", "--summary"});
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader);
  // Read until frames of a third pass arrived, then stop the replay with SIGINT. Stamps keep
  // increasing across passes, as a sensor's would, although the capture starts over.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  std::int64_t last_stamp = 0;
  std::uint64_t last_seq = 0;
  while (last_seq < 5 && std::chrono::steady_clock::now() < deadline) {
    if (reader->read_next(buffer, info, 100ms) != sim::ReadStatus::new_frame) continue;
    EXPECT_GT(info.stamp_ns, last_stamp) << "seq " << info.seq;
    last_stamp = info.stamp_ns;
    last_seq = info.seq;
  }
  looping.signal(SIGINT);
  ASSERT_EQ(looping.wait(), 0) << looping.err();
  EXPECT_GE(summary_value(looping.out(), "passes"), 3);
  EXPECT_EQ(summary_value(looping.out(), "malformed"), 0);
  // Loops restart the revolution: no packet loss is counted at the wrap.
  EXPECT_EQ(summary_value(looping.out(), "lost"), 0);

  // A window of the capture: skipping 0.2 s of 0.4 s leaves fewer whole revolutions.
  StreamGuard windowed;
  const auto result = run({replay_tool, p64_capture, "--stream", windowed.name, "--calibration",
                           p64_calibration, "--max-rate", "--start", "0.2", "--duration", "0.1",
                           "--summary"});
  ASSERT_EQ(result.code, 0) << result.err;
  EXPECT_LT(summary_value(result.out, "packets"), 2400);
  EXPECT_GT(summary_value(result.out, "packets"), 0);
  EXPECT_LE(summary_value(result.out, "frames"), 1);

  // --restamp moves the sensor's time to the present.
  const std::int64_t before = sim::realtime_ns();
  const auto restamped = run({replay_tool, p64_capture, "--stream", windowed.name, "--calibration",
                              p64_calibration, "--max-rate", "--restamp"});
  ASSERT_EQ(restamped.code, 0) << restamped.err;
  auto newest = sim::Reader::open(windowed.name);
  ASSERT_TRUE(newest);
  std::vector<std::byte> frame(newest->capacity());
  sim::FrameInfo newest_info;
  ASSERT_EQ(newest->read(frame, newest_info), sim::ReadStatus::new_frame);
  EXPECT_GT(newest_info.stamp_ns, before);
  EXPECT_LT(newest_info.stamp_ns, sim::realtime_ns() + 1'000'000'000);

  const auto beyond = run({replay_tool, p64_capture, "--stream", windowed.name, "--calibration",
                           p64_calibration, "--max-rate", "--start", "5"});
  EXPECT_EQ(beyond.code, 1);
  EXPECT_NE(beyond.err.find("holds no packet"), std::string::npos) << beyond.err;
}

TEST(ReplayTool, EveryLoopPublishesTheRecordedRevolutionsOnePeriodApart) {
  // A looping replay must publish, pass after pass, exactly the revolutions of the recording
  // (what a test compares with a reference cloud), in order, with stamps one sensor period apart
  // across the wrap as within a pass; never a revolution spliced from the capture's end and start.
  const auto expected =
      decode_directly(payloads_of(p64_capture), sim::hesai::Model::pandar64, p64_calibration);
  ASSERT_GE(expected.size(), 2u);
  const std::int64_t period = (expected.back().stamp_ns - expected.front().stamp_ns) /
                              static_cast<std::int64_t>(expected.size() - 1);
  StreamGuard stream;
  Process looping({replay_tool, p64_capture, "--stream", stream.name, "--calibration",
                   p64_calibration, "--loop", "--restamp", "--summary"});
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<int> times_seen(expected.size(), 0);
  std::vector<std::byte> buffer(reader->capacity());
  std::optional<std::size_t> previous;  // which revolution the previous frame was
  sim::FrameInfo previous_info;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  // Until every revolution came at least three times: the first pass and two loops.
  while (*std::min_element(times_seen.begin(), times_seen.end()) < 3 &&
         std::chrono::steady_clock::now() < deadline) {
    sim::FrameInfo info;
    if (reader->read_next(buffer, info, 100ms) != sim::ReadStatus::new_frame) continue;
    std::vector<sim::LidarPoint> points(info.size / sizeof(sim::LidarPoint));
    std::memcpy(points.data(), buffer.data(), info.size);
    std::optional<std::size_t> which;
    for (std::size_t k = 0; k < expected.size() && !which; ++k) {
      if (same_points(points, expected[k].points)) which = k;
    }
    ASSERT_TRUE(which) << "frame " << info.seq << " (" << points.size()
                       << " points) is none of the recorded revolutions";
    ++times_seen[*which];
    if (previous && info.seq == previous_info.seq + 1) {  // the reader saw both: compare them
      EXPECT_EQ(*which, (*previous + 1) % expected.size()) << "frame " << info.seq;
      const std::int64_t step = info.stamp_ns - previous_info.stamp_ns;
      if (*which > *previous) {
        EXPECT_EQ(step, expected[*which].stamp_ns - expected[*previous].stamp_ns)
            << "frame " << info.seq;
      } else {  // the wrap
        EXPECT_GT(step, period * 95 / 100) << "frame " << info.seq;
        EXPECT_LT(step, period * 105 / 100) << "frame " << info.seq;
      }
    }
    previous = which;
    previous_info = info;
  }
  looping.signal(SIGINT);
  ASSERT_EQ(looping.wait(), 0) << looping.err();
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_GE(times_seen[k], 3) << "revolution " << k << " of the recording";
  }
  EXPECT_GE(summary_value(looping.out(), "passes"), 3);
  EXPECT_EQ(summary_value(looping.out(), "lost"), 0);
}

TEST(ReplayTool, BadInputGetsOneSentenceAndExitCode) {
  const fs::path dir = fs::temp_directory_path() / ("sim_replay_bad_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  StreamGuard stream;
  auto replay = [&](std::vector<std::string> extra) {
    std::vector<std::string> argv = {replay_tool};
    argv.insert(argv.end(), extra.begin(), extra.end());
    argv.insert(argv.end(), {"--stream", stream.name, "--max-rate"});
    return run(argv);
  };

  {  // cut in the middle of a record: the whole records are replayed, then exit 1
    std::ifstream in(p64_capture, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes.resize(bytes.size() * 9 / 10 + 100);
    std::ofstream((dir / "cut.pcap").string(), std::ios::binary)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    const auto r = replay({(dir / "cut.pcap").string(), "--calibration", p64_calibration, "--summary"});
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("cut short"), std::string::npos) << r.err;
    EXPECT_GE(summary_value(r.out, "frames"), 1);
  }
  {  // a capture of another protocol
    using namespace sim::pcap::testing;
    std::vector<Record> records;
    for (int i = 0; i < 4; ++i) {
      records.push_back({ethernet(0x0800, ipv4({10, 0, 0, 1}, {10, 0, 0, 2}, Bytes(60, 0), 6)), i});
    }
    write_capture((dir / "tcp.pcap").string(), DLT_EN10MB, records);
    const auto r = replay({(dir / "tcp.pcap").string(), "--calibration", p64_calibration});
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("no UDP datagram"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not a LiDAR capture"), std::string::npos) << r.err;
  }
  {  // UDP, but not Hesai
    using namespace sim::pcap::testing;
    write_capture((dir / "dns.pcap").string(), DLT_EN10MB,
                  {{ethernet(0x0800, ipv4({10, 0, 0, 1}, {10, 0, 0, 2}, udp(53, 2368, Bytes(40, 1)))), 1}});
    const auto r = replay({(dir / "dns.pcap").string(), "--calibration", p64_calibration});
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("is a Hesai point-cloud packet"), std::string::npos) << r.err;
  }
  {  // a link type the reader does not parse
    using namespace sim::pcap::testing;
    write_capture((dir / "wifi.pcap").string(), DLT_IEEE802_11, {{Bytes(100, 0), 1}});
    const auto r = replay({(dir / "wifi.pcap").string(), "--calibration", p64_calibration});
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("link type"), std::string::npos) << r.err;
  }
  {  // the wrong model forced
    const auto r = replay({p64_capture, "--calibration", p64_calibration, "--model", "Pandar40P"});
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("holds Pandar64 packets, not Pandar40P"), std::string::npos) << r.err;
  }
  {  // a calibration file for another channel count
    const auto r = replay({p64_capture, "--calibration", (data_dir / "pandarxt32.calibration.csv").string()});
    EXPECT_EQ(r.code, 1);
    EXPECT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
  }
  {  // missing file, missing calibration, bad options
    const auto missing = replay({(dir / "nope.pcap").string(), "--calibration", p64_calibration});
    EXPECT_EQ(missing.code, 1);
    EXPECT_NE(missing.err.find("nope.pcap"), std::string::npos);
    EXPECT_EQ(replay({p64_capture}).code, 2);
    EXPECT_EQ(replay({p64_capture, "--calibration", p64_calibration, "--rate", "-1"}).code, 2);
    EXPECT_EQ(replay({p64_capture, "--calibration", p64_calibration, "--model", "Velodyne"}).code, 2);
    EXPECT_EQ(run({replay_tool, "--help"}).code, 0);
  }
  fs::remove_all(dir);
}

// ---- live driver ------------------------------------------------------------------------------

class UdpSender {
 public:
  // `from`: the loopback address to send from (all of 127/8 is local on Linux), 0 for any.
  // `to`: the destination, loopback or a multicast group (sent out of the loopback device).
  explicit UdpSender(int port, std::uint32_t from = 0, std::uint32_t to = INADDR_LOOPBACK)
      : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    if (IN_MULTICAST(to)) {
      in_addr loopback{};
      loopback.s_addr = htonl(INADDR_LOOPBACK);
      ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_IF, &loopback, sizeof loopback);
      const unsigned char loop = 1;
      ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
    }
    if (from != 0) {
      sockaddr_in local{};
      local.sin_family = AF_INET;
      local.sin_addr.s_addr = htonl(from);
      ::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local);
    }
    to_.sin_family = AF_INET;
    to_.sin_port = htons(static_cast<std::uint16_t>(port));
    to_.sin_addr.s_addr = htonl(to);
  }
  ~UdpSender() { ::close(fd_); }
  void send(const std::vector<std::uint8_t>& bytes) {
    ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to_), sizeof to_);
  }
  // Sends all payloads at once, with as few system calls as sendmmsg allows (1024 datagrams
  // each): the receiver sees them arrive within microseconds of each other, however this
  // process is scheduled. The driver's receive buffer (16 MiB) holds a whole capture.
  void send_burst(const std::vector<Payload>& payloads) {
    for (std::size_t first = 0; first < payloads.size(); first += 1024) {
      const std::size_t count = std::min<std::size_t>(1024, payloads.size() - first);
      std::vector<iovec> vectors(count);
      std::vector<mmsghdr> headers(count);
      for (std::size_t i = 0; i < count; ++i) {
        auto& bytes = payloads[first + i].bytes;
        vectors[i] = {const_cast<std::uint8_t*>(bytes.data()), bytes.size()};
        headers[i] = {};
        headers[i].msg_hdr.msg_name = &to_;
        headers[i].msg_hdr.msg_namelen = sizeof to_;
        headers[i].msg_hdr.msg_iov = &vectors[i];
        headers[i].msg_hdr.msg_iovlen = 1;
      }
      std::size_t sent = 0;
      while (sent < count) {
        const int n = ::sendmmsg(fd_, headers.data() + sent, static_cast<unsigned>(count - sent), 0);
        if (n <= 0) break;
        sent += static_cast<std::size_t>(n);
      }
    }
  }
  // Sends payloads spaced as they were captured (slowed by `slowdown`), like a sensor.
  void send_paced(const std::vector<Payload>& payloads, double slowdown = 1.0) {
    const auto start = std::chrono::steady_clock::now();
    for (const Payload& p : payloads) {
      const auto offset = std::chrono::nanoseconds(static_cast<std::int64_t>(
          static_cast<double>(p.timestamp_ns - payloads.front().timestamp_ns) * slowdown));
      std::this_thread::sleep_until(start + offset);
      send(p.bytes);
    }
  }

 private:
  int fd_;
  sockaddr_in to_{};
};

// Feeds `payloads` one revolution per burst and waits for each revolution's frame before the
// next burst (a SIM reader sees the newest frame, so it must keep up), returning the frames.
// Where the revolutions end is worked out with the decoder library.
std::vector<Frame> send_revolution_by_revolution(UdpSender& sender, sim::Reader& reader,
                                                 const std::vector<Payload>& payloads,
                                                 sim::hesai::Model model,
                                                 const std::string& calibration_path) {
  auto calibration = sim::hesai::Calibration::load(calibration_path, model);
  EXPECT_TRUE(calibration);
  sim::hesai::AssemblerOptions options;
  options.model = model;
  auto assembler = sim::hesai::FrameAssembler::create(std::move(calibration.value()), options);
  std::vector<sim::LidarPoint> scratch(sim::hesai::frame_capacity(model));
  assembler->set_output(scratch);
  std::vector<Frame> frames;
  std::size_t begin = 0;
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    if (!assembler->push(payloads[i].bytes, 0).frame) continue;
    assembler->set_output(scratch);
    sender.send_burst({payloads.begin() + static_cast<std::ptrdiff_t>(begin),
                       payloads.begin() + static_cast<std::ptrdiff_t>(i + 1)});
    begin = i + 1;
    auto got = receive_frames(reader, 1);
    if (got.empty()) return frames;
    frames.push_back(std::move(got.front()));
  }
  sender.send_burst({payloads.begin() + static_cast<std::ptrdiff_t>(begin), payloads.end()});
  return frames;
}

// Waits (up to 60 s) until no datagram waits in the receive queue of this network namespace's
// UDP socket on `port` (/proc/net/udp's rx_queue): every datagram sent has been taken by the
// driver, whose loop handles what it took before it looks at a stop request. A SIGTERM sent at
// once after the last burst could otherwise end the driver with that burst still queued (seen
// under AddressSanitizer). True when drained.
bool wait_until_taken(int port) {
  char local[16];
  std::snprintf(local, sizeof local, ":%04X ", port);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream table("/proc/net/udp");
    std::string line;
    bool queued = false;
    while (std::getline(table, line)) {
      // "sl local_address rem_address st tx_queue:rx_queue …"
      const auto at = line.find(local);
      if (at == std::string::npos || at > 24) continue;
      const auto colon = line.find(':', line.find(' ', line.find(' ', at + 1) + 1) + 1);
      if (colon != std::string::npos && std::strtoul(line.c_str() + colon + 1, nullptr, 16) != 0) queued = true;
    }
    if (!queued) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

int listening_port(Process& driver) {
  const auto line = driver.wait_for_line("listening on");
  if (!line) return -1;
  return std::stoi(line->substr(line->rfind(':') + 1));
}

TEST(LiveDriver, SameFramesAsReplayOverUdpLoopback) {
  const auto payloads = payloads_of(p64_capture);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);
  StreamGuard stream;
  Process driver({live_tool, "--model", "Pandar64", "--port", "0", "--bind", "127.0.0.1",
                  "--stream", stream.name, "--calibration", p64_calibration,
                  "--status-interval", "0", "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;

  UdpSender sender(port);
  const std::int64_t first_send_ns = sim::realtime_ns();
  std::thread feed([&] { sender.send_paced(payloads, 2.0); });
  const auto frames = receive_frames(*reader, expected.size());
  feed.join();
  const std::int64_t last_send_ns = sim::realtime_ns();
  // Beside the sensor's stamp, each frame carries when this host received its first packet.
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_GE(frames[i].receive_ns, first_send_ns) << "frame " << i;
    EXPECT_LE(frames[i].receive_ns, last_send_ns) << "frame " << i;
    if (i > 0) {
      EXPECT_GT(frames[i].receive_ns, frames[i - 1].receive_ns) << "frame " << i;
    }
  }
  driver.signal(SIGTERM);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  expect_same_frames(frames, expected, 1);
  EXPECT_EQ(summary_value(driver.out(), "frames"), static_cast<long long>(expected.size()));
  EXPECT_EQ(summary_value(driver.out(), "lost"), 0);
  EXPECT_EQ(summary_value(driver.out(), "malformed"), 0);
}

TEST(LiveDriver, CountsBadPacketsAndResumesAfterSilence) {
  // What a user relies on: junk on the port is counted and harms no frame; while the sensor is
  // quiet the last frame stays readable and turns stale; when the sensor starts over, the
  // half-finished revolution from before the silence is not mixed into the new frames, which
  // are numbered on. Packets go out one revolution per sendmmsg burst, the next burst as soon
  // as the reader has the frame, and the driver measures silence between kernel arrival
  // stamps: the only gap near the timeout (2 s) is the test's own 2.5 s pause, so neither a
  // slow driver nor a slow sender fakes a silence short of a two-second freeze.
  const auto payloads = payloads_of(p64_capture);
  const std::vector<Payload> first_half(payloads.begin(), payloads.begin() + 1900);
  const auto expected_first = decode_directly(first_half, sim::hesai::Model::pandar64, p64_calibration);
  const auto expected_all = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);
  ASSERT_GE(expected_first.size(), 1u);

  StreamGuard stream;
  Process driver({live_tool, "--model", "Pandar64", "--port", "0", "--bind", "127.0.0.1",
                  "--stream", stream.name, "--calibration", p64_calibration,
                  "--status-interval", "0", "--silence-timeout", "2", "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  sim::ReaderOptions options;
  options.stale_after = 150ms;
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader);
  UdpSender sender(port);

  // Junk first: a cut-short packet, garbage, and an XT32 packet on the Pandar64's port.
  const auto xt32 = payloads_of((data_dir / "pandarxt32_dual.pcap").string());
  const std::vector<Payload> first_pass{
      {std::vector<std::uint8_t>(payloads[0].bytes.begin(), payloads[0].bytes.begin() + 500), 0},
      {std::vector<std::uint8_t>(1198, 0x5a), 0},
      xt32.at(0)};
  sender.send_burst(first_pass);
  const auto frames = send_revolution_by_revolution(sender, *reader, first_half,
                                                    sim::hesai::Model::pandar64, p64_calibration);
  expect_same_frames(frames, expected_first, 1);

  // The sensor goes quiet: the region stays, with its newest frame, and turns stale.
  auto stale_reader = sim::Reader::open(stream.name, options);
  ASSERT_TRUE(stale_reader);
  std::vector<std::byte> buffer(stale_reader->capacity());
  sim::FrameInfo info;
  ASSERT_EQ(stale_reader->read(buffer, info), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.seq, expected_first.size());
  std::this_thread::sleep_for(2500ms);
  EXPECT_EQ(stale_reader->read(buffer, info), sim::ReadStatus::stale);
  EXPECT_TRUE(stale_reader->writer_alive());

  // Packets come back (the sensor restarts its revolution): frames resume, numbered on, and
  // equal to the decoder's frames of the new pass alone.
  const auto resumed = send_revolution_by_revolution(sender, *reader, payloads,
                                                     sim::hesai::Model::pandar64, p64_calibration);
  driver.signal(SIGINT);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  expect_same_frames(resumed, expected_all, expected_first.size() + 1);
  EXPECT_EQ(summary_value(driver.out(), "resumes"), 1);
  EXPECT_EQ(summary_value(driver.out(), "malformed"), 2);
  EXPECT_EQ(summary_value(driver.out(), "wrong_model"), 1);
  EXPECT_EQ(summary_value(driver.out(), "frames"),
            static_cast<long long>(expected_first.size() + expected_all.size()));
}

TEST(LiveDriver, PandarQT128ReplayAndLiveUdpGiveIdenticalFrames) {
  const std::string capture = (data_dir / "pandarqt128_dual.pcap").string();
  const std::string calibration = (data_dir / "pandarqt128.calibration.csv").string();
  const auto payloads = payloads_of(capture);
  ASSERT_EQ(payloads.size(), 1800u);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar_qt128, calibration);
  ASSERT_GE(expected.size(), 1u);

  // Through SIM from the capture file (model detected from the packets).
  StreamGuard replayed;
  Process replay({replay_tool, capture, "--stream", replayed.name, "--calibration", calibration,
                  "--rate", "0.5", "--summary"});
  auto replay_reader = open_when_created(replayed.name);
  ASSERT_TRUE(replay_reader) << replay_reader.error().message;
  const auto from_replay = receive_frames(*replay_reader, expected.size());
  ASSERT_EQ(replay.wait(), 0) << replay.err();
  EXPECT_EQ(summary_value(replay.out(), "crc_errors"), 0);

  // Live, the same payloads over UDP on loopback (model detected from the first packet).
  StreamGuard live;
  Process driver({live_tool, "--port", "0", "--bind", "127.0.0.1", "--stream", live.name,
                  "--calibration", calibration, "--status-interval", "0", "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  UdpSender sender(port);
  sender.send_burst(payloads);
  auto live_reader = open_when_created(live.name);
  ASSERT_TRUE(live_reader) << live_reader.error().message;
  const auto from_live = receive_frames(*live_reader, expected.size());
  driver.signal(SIGTERM);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  EXPECT_NE(driver.err().find("detected a PandarQT128"), std::string::npos) << driver.err();

  expect_same_frames(from_replay, expected, 1);
  expect_same_frames(from_live, from_replay, 1);
  EXPECT_EQ(summary_value(driver.out(), "packets"), 1800);
  EXPECT_EQ(summary_value(driver.out(), "crc_errors"), 0);
  EXPECT_EQ(summary_value(driver.out(), "lost"), 0);
  EXPECT_EQ(summary_value(driver.out(), "rpm"), 600);
  EXPECT_NE(driver.out().find("safety=initialization"), std::string::npos) << driver.out();
}

// Sensors are often set to send to a multicast group. A real group needs a multicast-capable
// device with a route for 224.0.0.0/4, which the test gets in a private network namespace
// (unshare --net): the test runs itself again inside one, with loopback up, multicast on and
// the route added, and the inner run does the work.
TEST(LiveDriver, MulticastGroupGivesTheSameFramesAsReplay) {
  if (std::getenv("SIM_HESAI_IN_NETNS") == nullptr) {
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const std::string script =
        "PATH=/usr/sbin:/sbin:$PATH; ip link set lo up && ip link set lo multicast on && "
        "ip route add 224.0.0.0/4 dev lo && SIM_HESAI_IN_NETNS=1 exec \"$0\" "
        "--gtest_filter=LiveDriver.MulticastGroupGivesTheSameFramesAsReplay";
    ASSERT_TRUE(fs::exists("/usr/bin/unshare"))
        << "unshare (util-linux) is needed; scripts/install-deps.sh installs it";
    const auto inner = run({"/usr/bin/unshare", "--net", "--", "/bin/sh", "-c", script, self});
    if (inner.code != 0 && inner.err.find("unshare failed") != std::string::npos) {
      GTEST_SKIP() << "unshare --net is not permitted here (it needs root or CAP_SYS_ADMIN), so "
                      "the multicast test cannot make its private network: "
                   << inner.err;
    }
    ASSERT_EQ(inner.code, 0) << inner.out << inner.err;
    EXPECT_NE(inner.out.find("[  PASSED  ] 1 test"), std::string::npos) << inner.out;
    return;
  }

  const std::uint32_t group = 0xEFFF2A01;  // 239.255.42.1, administratively scoped
  const auto payloads = payloads_of(p64_capture);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);

  StreamGuard replayed;
  Process replay({replay_tool, p64_capture, "--stream", replayed.name, "--calibration",
                  p64_calibration, "--rate", "0.5", "--summary"});
  auto replay_reader = open_when_created(replayed.name);
  ASSERT_TRUE(replay_reader) << replay_reader.error().message;
  const auto from_replay = receive_frames(*replay_reader, expected.size());
  ASSERT_EQ(replay.wait(), 0) << replay.err();

  StreamGuard live;
  // The test waits for each revolution's frame before it sends the next, as long as the machine
  // makes it (seconds under ASan on a loaded host): no such pause may read as a silence of the
  // sensor, which would drop the next revolution as one begun mid-way.
  Process driver({live_tool, "--model", "Pandar64", "--port", "0", "--bind", "0.0.0.0",
                  "--multicast-group", "239.255.42.1", "--stream", live.name, "--calibration",
                  p64_calibration, "--status-interval", "0", "--silence-timeout", "120", "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  auto reader = open_when_created(live.name);
  ASSERT_TRUE(reader) << reader.error().message;
  UdpSender sender(port, 0, group);
  const auto from_live = send_revolution_by_revolution(sender, *reader, payloads,
                                                       sim::hesai::Model::pandar64, p64_calibration);
  EXPECT_TRUE(wait_until_taken(port)) << "the driver left datagrams queued for a minute";
  driver.signal(SIGTERM);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  expect_same_frames(from_replay, expected, 1);
  expect_same_frames(from_live, from_replay, 1);
  EXPECT_EQ(summary_value(driver.out(), "packets"), 2400);
  EXPECT_EQ(summary_value(driver.out(), "lost"), 0);
}

TEST(LiveDriver, SourceFilterIgnoresOtherSenders) {
  const auto payloads = payloads_of(p64_capture);
  const auto expected = decode_directly(payloads, sim::hesai::Model::pandar64, p64_calibration);
  StreamGuard stream;
  Process driver({live_tool, "--model", "Pandar64", "--port", "0", "--bind", "0.0.0.0",
                  "--source", "127.0.0.2", "--stream", stream.name, "--calibration",
                  p64_calibration, "--status-interval", "0", "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader);
  UdpSender stranger(port, 0x7f000001);  // 127.0.0.1: another device on the port
  for (int i = 0; i < 600; ++i) stranger.send(payloads[static_cast<std::size_t>(i)].bytes);
  UdpSender sensor(port, 0x7f000002);    // 127.0.0.2: the sensor
  std::thread feed([&] { sensor.send_paced(payloads, 2.0); });
  const auto frames = receive_frames(*reader, expected.size());
  feed.join();
  driver.signal(SIGTERM);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  // The stranger's packets, sent first, were all seen and none went into a frame.
  expect_same_frames(frames, expected, 1);
  EXPECT_EQ(summary_value(driver.out(), "other_source"), 600);
  EXPECT_EQ(summary_value(driver.out(), "lost"), 0);
}

TEST(LiveDriver, ConfigFileAndAutoDetectedModel) {
  const fs::path dir = fs::temp_directory_path() / ("sim_live_cfg_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::copy_file(p64_calibration, dir / "unit.csv", fs::copy_options::overwrite_existing);
  StreamGuard stream;
  std::ofstream(dir / "lidar.yaml") << "# test config\nmodel: auto\nport: 0\nbind: 127.0.0.1\n"
                                    << "stream: " << stream.name << "\ncalibration: unit.csv\n"
                                    << "status_interval: 0\n";
  Process driver({live_tool, "--config", (dir / "lidar.yaml").string(), "--summary"});
  const int port = listening_port(driver);
  ASSERT_GT(port, 0) << driver.err();
  const auto payloads = payloads_of(p64_capture);
  UdpSender sender(port);
  sender.send(std::vector<std::uint8_t>(64, 1));  // not Hesai: ignored before detection
  std::thread feed([&] { sender.send_paced(payloads, 2.0); });
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader);
  const auto frames = receive_frames(*reader, 1);
  feed.join();
  driver.signal(SIGTERM);
  ASSERT_EQ(driver.wait(), 0) << driver.err();
  EXPECT_EQ(frames.size(), 1u);
  EXPECT_NE(driver.err().find("detected a Pandar64"), std::string::npos) << driver.err();
  EXPECT_EQ(summary_value(driver.out(), "unrecognised"), 1);

  // An unknown key is refused by name.
  std::ofstream(dir / "typo.yaml") << "model: Pandar64\ncalibraton: unit.csv\n";
  const auto typo = run({live_tool, "--config", (dir / "typo.yaml").string()});
  EXPECT_EQ(typo.code, 2);
  EXPECT_NE(typo.err.find("no option named 'calibraton'"), std::string::npos) << typo.err;
  fs::remove_all(dir);
}

TEST(LiveDriver, ShippedConfigFilesStartTheDriver) {
  // config/hesai/*.yaml with the test's calibration and a free port: each must parse and start.
  const std::vector<std::pair<std::string, std::string>> configs = {
      {"pandar64.yaml", "pandar64.calibration.csv"},
      {"pandar40p.yaml", "pandar40p.example-calibration.csv"},
      {"pandarxt32.yaml", "pandarxt32.calibration.csv"},
      {"pandarqt128.yaml", "pandarqt128.calibration.csv"}};
  for (const auto& [config, calibration] : configs) {
    StreamGuard stream;
    Process driver({live_tool, "--config", (fs::path(SIM_CONFIG_DIR) / "hesai" / config).string(),
                    "--port", "0", "--bind", "127.0.0.1", "--stream", stream.name,
                    "--calibration", (data_dir / calibration).string(), "--status-interval", "0"});
    EXPECT_GT(listening_port(driver), 0) << config << ": " << driver.err();
    auto reader = open_when_created(stream.name);
    EXPECT_TRUE(reader) << config;
    driver.signal(SIGTERM);
    EXPECT_EQ(driver.wait(), 0) << config << ": " << driver.err();
  }
}

TEST(LiveDriver, PortInUseIsAClearErrorAndExitOne) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  const int port = ntohs(address.sin_port);
  StreamGuard stream;
  const auto result = run({live_tool, "--model", "Pandar64", "--bind", "127.0.0.1", "--port",
                           std::to_string(port), "--stream", stream.name, "--calibration",
                           p64_calibration});
  ::close(fd);
  EXPECT_EQ(result.code, 1);
  EXPECT_NE(result.err.find("UDP port " + std::to_string(port) + " on 127.0.0.1 is already in use"),
            std::string::npos)
      << result.err;
  // Nothing was created for a driver that could not start.
  EXPECT_FALSE(sim::Reader::open(stream.name));
}

TEST(LiveDriver, UsageErrors) {
  EXPECT_EQ(run({live_tool, "--help"}).code, 0);
  EXPECT_EQ(run({live_tool, "--model", "Pandar64"}).code, 2);  // no calibration
  EXPECT_EQ(run({live_tool, "--calibration", p64_calibration, "--bind", "not-an-ip"}).code, 2);
  EXPECT_EQ(run({live_tool, "--calibration", p64_calibration, "--port", "70000"}).code, 2);
}

}  // namespace

namespace {

// The description a reader finds in `stream` (the test fails when there is none).
std::optional<sim::SensorInfo> sensor_info_of(const sim::Reader& reader) {
  auto info = reader.sensor_info();
  if (!info) {
    ADD_FAILURE() << info.error().message;
    return std::nullopt;
  }
  return *info;
}

}  // namespace

TEST(ReplayTool, TheStreamCarriesTheFrameMountingAndCalibrationSourceGiven) {
  StreamGuard stream;
  Process replay({replay_tool, p64_capture, "--stream", stream.name, "--calibration",
                  p64_calibration, "--loop", "--frame-id", "lidar_top", "--parent-frame",
                  "roof_rack", "--x", "1.25", "--z", "1.8", "--yaw", "3.0"});
  auto reader = open_when_created(stream.name);
  ASSERT_TRUE(reader) << reader.error().message;
  const auto info = sensor_info_of(*reader);
  ASSERT_TRUE(info.has_value()) << "the stream carries no description";
  EXPECT_EQ(info->frame_id, "lidar_top");
  EXPECT_EQ(info->parent_frame, "roof_rack");
  ASSERT_TRUE(info->mounting.has_value());
  EXPECT_EQ(info->mounting->translation, (std::array<double, 3>{1.25, 0.0, 1.8}));
  EXPECT_EQ(info->mounting->rotation, sim::Mounting::from_xyz_rpy(0, 0, 0, 0, 0, 3.0).rotation);
  EXPECT_EQ(info->identity.vendor, "Hesai");
  EXPECT_EQ(info->identity.model, "Pandar64");
  EXPECT_EQ(info->point_time, sim::PointTime::after_frame_stamp);
  EXPECT_EQ(info->calibration_source,
            "file://" + fs::absolute(p64_calibration).lexically_normal().string());
  EXPECT_FALSE(info->calibration.has_value());
  replay.signal(SIGTERM);
  EXPECT_EQ(replay.wait(), 0) << replay.err();
}

// Which clock the replayed stamps are: this host's with --restamp, otherwise the sensor's as
// recorded, whose synchronisation a Hesai capture does not show.
TEST(ReplayTool, TheStreamSaysWhichClockItsStampsAreWithAndWithoutRestamp) {
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
    StreamGuard stream;
    std::vector<std::string> argv{replay_tool, p64_capture, "--stream", stream.name, "--calibration",
                                  p64_calibration, "--max-rate"};
    if (expected.restamp) argv.push_back("--restamp");
    const auto r = run(argv);
    ASSERT_EQ(r.code, 0) << r.err;
    auto reader = sim::Reader::open(stream.name);
    ASSERT_TRUE(reader) << reader.error().message;
    const auto info = sensor_info_of(*reader);
    ASSERT_TRUE(info.has_value()) << "the stream carries no description";
    EXPECT_EQ(info->time_base, expected.time_base) << "restamp " << expected.restamp;
    EXPECT_EQ(info->time_sync, expected.time_sync) << "restamp " << expected.restamp;
  }
}

TEST(ReplayTool, ABadFrameNameOrMountingIsRefusedWithOneSentenceAndNoStream) {
  StreamGuard stream;
  const std::vector<std::vector<std::string>> bad = {
      {"--frame-id", "lidar top"}, {"--frame-id", "cam\xc3\xa9ra"}, {"--parent-frame", "/base_link"},
      {"--x", "nan"}, {"--yaw", "inf"}};
  for (const auto& extra : bad) {
    std::vector<std::string> argv = {replay_tool, p64_capture, "--stream", stream.name,
                                     "--calibration", p64_calibration, "--max-rate"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    const auto r = run(argv);
    EXPECT_EQ(r.code, 2) << extra[0] << " " << extra[1] << ": " << r.err;
    EXPECT_EQ(r.err.rfind("sim_replay_pcap: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
    auto reader = sim::Reader::open(stream.name);
    ASSERT_FALSE(reader) << "a stream was created for " << extra[0] << " " << extra[1];
    EXPECT_EQ(reader.error().code, sim::ErrorCode::not_found);
  }
}
