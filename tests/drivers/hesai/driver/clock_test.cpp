// SPDX-License-Identifier: Apache-2.0
// The clock check of sim_replay_pcap on real Hesai recordings, as a real process: the offset it
// writes to the stream is the one this test computes from the capture itself (each packet's
// sensor time minus its capture time, the median), and the same packets with their sensor times
// rewritten here (+37 s, −1 h, 1970, a 2 s step, +100 ppm) each get their sentence, while
// rewritten to agree with the capture they get ok. Read back with a sim::Reader (Reader::clock()).
// The live driver, fed the same packets on loopback in a private network namespace, judges them
// against their arrival the same way.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "lidar_test/capture_frames.hpp"
#include "sim/clock_status.hpp"
#include "sim/hesai/hesai.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/ouster/frame_assembler.hpp"
#include "sim/ouster/metadata.hpp"
#include "sim/ouster/packet.hpp"
#include "sim/velodyne/frame_assembler.hpp"
#include "sim/velodyne/model.hpp"
#include "sim/velodyne/packet.hpp"
#include "sim/pcap/capture.hpp"
#include "sim/reader.hpp"
#include "sim/clock.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

namespace fs = std::filesystem;
namespace pt = sim::pcap::testing;
using sim::ClockStatus;
using sim::ClockVerdict;

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kS = 1'000'000'000;
constexpr double kYearNs = 365.25 * 86400.0 * 1e9;

std::optional<std::string> g_no_network;  // why the private network namespace is missing
const fs::path data_dir = SIM_HESAI_TEST_DATA;
const std::string replay_tool = SIM_REPLAY_PCAP;

struct Packet {
  std::vector<std::uint8_t> bytes;
  std::int64_t capture_ns = 0;
  std::int64_t sensor_ns = 0;  // the packet's own time, as the decoder reads its tail
};

// The Hesai packets of a capture with their capture and sensor times.
std::vector<Packet> packets_of(const fs::path& path, sim::hesai::Model model) {
  auto reader = sim::pcap::CaptureReader::open(path.string());
  EXPECT_TRUE(reader) << reader.error().message;
  std::vector<Packet> out;
  sim::pcap::Datagram d;
  while (reader && reader->next(d) == sim::pcap::NextStatus::datagram) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(d.payload.data());
    Packet packet{{p, p + d.payload.size()}, d.timestamp_ns, 0};
    sim::hesai::Packet parsed;
    if (sim::hesai::Packet::parse(packet.bytes, model, parsed) != sim::hesai::PacketError::none) continue;
    packet.sensor_ns = parsed.time_ns();
    out.push_back(std::move(packet));
  }
  return out;
}

std::int64_t median(std::vector<std::int64_t> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>((values.size() - 1) / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

std::int64_t median_offset(const std::vector<Packet>& packets) {
  std::vector<std::int64_t> offsets;
  for (const Packet& p : packets) offsets.push_back(p.sensor_ns - p.capture_ns);
  return median(offsets);
}

// The Pandar64 tail's time: six date bytes (year − 1900, or the year of 1970 for a clock that
// counts from power-on) and the µs (docs/hesai.md).
constexpr std::size_t p64_tail = 8 + 6 * 194;
void write_p64_time(std::vector<std::uint8_t>& bytes, std::int64_t ns) {
  const std::time_t seconds = static_cast<std::time_t>(ns / kS);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  const auto micros = static_cast<std::uint32_t>((ns % kS) / 1000);
  std::uint8_t* date = bytes.data() + p64_tail + 16;
  date[0] = static_cast<std::uint8_t>(tm.tm_year);
  date[1] = static_cast<std::uint8_t>(tm.tm_mon + 1);
  date[2] = static_cast<std::uint8_t>(tm.tm_mday);
  date[3] = static_cast<std::uint8_t>(tm.tm_hour);
  date[4] = static_cast<std::uint8_t>(tm.tm_min);
  date[5] = static_cast<std::uint8_t>(tm.tm_sec);
  for (int i = 0; i < 4; ++i) bytes[p64_tail + 10 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(micros >> (8 * i));
}

// The recorded Pandar64 packets laid end to end for `seconds` (every 16th packet, to keep the file
// small: the clock check needs times, not points), each packet's sensor time rewritten to its
// new capture time plus `offset(t, start)` (t: since the capture's start) plus the packet's own
// recorded jitter.
fs::path rewritten_capture(const fs::path& dir, const std::string& name, double seconds,
                           const std::function<std::int64_t(std::int64_t, std::int64_t)>& offset) {
  const auto recorded = packets_of(data_dir / "pandar64_dual.pcap", sim::hesai::Model::pandar64);
  EXPECT_GT(recorded.size(), 1000u);
  const std::int64_t typical = median_offset(recorded);
  const std::int64_t start = recorded.front().capture_ns;
  const std::int64_t tile = recorded.back().capture_ns - start + 200'000;
  std::vector<pt::Record> records;
  for (std::int64_t shift = 0; shift < static_cast<std::int64_t>(seconds * 1e9); shift += tile) {
    for (std::size_t i = 0; i < recorded.size(); i += 16) {
      const Packet& p = recorded[i];
      std::vector<std::uint8_t> bytes = p.bytes;
      const std::int64_t capture = p.capture_ns + shift;
      const std::int64_t jitter = p.sensor_ns - p.capture_ns - typical;
      write_p64_time(bytes, capture + jitter + offset(capture - start, start));
      records.push_back({pt::ethernet(0x0800, pt::ipv4({192, 168, 1, 201}, {255, 255, 255, 255},
                                                        pt::udp(10000, 2368, bytes))),
                         capture});
    }
  }
  const fs::path path = dir / (name + ".pcap");
  pt::write_capture(path.string(), DLT_EN10MB, records, /*nanosecond=*/true);
  return path;
}

// A folder for the rewritten captures, removed when the test ends.
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("sim_hesai_clock_" + std::to_string(::getpid()) + "_" +
                                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { fs::create_directories(path); }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

// Each packet's own time, as the family's decoder reads it (nullopt: not one of its packets),
// against its capture time: the median.
std::int64_t median_offset(const fs::path& capture,
                           const std::function<std::optional<std::int64_t>(std::span<const std::uint8_t>, std::int64_t)>& time_of,
                           std::size_t& packets) {
  auto reader = sim::pcap::CaptureReader::open(capture.string());
  EXPECT_TRUE(reader) << reader.error().message;
  std::vector<std::int64_t> offsets;
  sim::pcap::Datagram d;
  while (reader && reader->next(d) == sim::pcap::NextStatus::datagram) {
    const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(d.payload.data()), d.payload.size());
    if (const auto sensor = time_of(bytes, d.timestamp_ns)) offsets.push_back(*sensor - d.timestamp_ns);
  }
  packets = offsets.size();
  EXPECT_FALSE(offsets.empty());
  return offsets.empty() ? 0 : median(offsets);
}

// Replays the capture to its end (as fast as it goes: the check measures against capture times,
// not the pace) and reads the clock the replay left in the stream.
ClockStatus replayed_clock(const fs::path& capture, const fs::path& calibration,
                           const std::vector<std::string>& extra = {"--max-rate"}) {
  sim::testing::StreamGuard stream(sim::testing::unique_name("hesai_clock"));
  stream.names.push_back(stream.name + ".imu");  // an Ouster replay's IMU stream goes too
  std::vector<std::string> argv{replay_tool, capture.string(), "--stream", stream.name, "--calibration",
                                (calibration.is_absolute() ? calibration : data_dir / calibration).string(), "--quiet"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  const auto run = sim::testing::run(argv);
  EXPECT_EQ(run.code, 0) << run.err;
  auto reader = sim::Reader::open(stream.name);
  EXPECT_TRUE(reader) << reader.error().message;
  if (!reader) return {};
  auto clock = reader->clock();
  EXPECT_TRUE(clock) << clock.error().message;
  if (!clock || !*clock) {
    ADD_FAILURE() << "the replay left no clock in the stream";
    return {};
  }
  return **clock;
}

std::string one_decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", value);
  return text;
}

bool says(const ClockStatus& clock, const std::string& words) {
  return clock.problem.find(words) != std::string::npos;
}

struct Recording {
  const char* capture;
  const char* calibration;
  sim::hesai::Model model;
};

TEST(HesaiReplayClock, measures_the_recorded_offset_and_says_how_many_years_behind) {
  for (const Recording& r : {Recording{"pandar64_dual.pcap", "pandar64.calibration.csv", sim::hesai::Model::pandar64},
                             Recording{"pandarxt32_dual.pcap", "pandarxt32.calibration.csv", sim::hesai::Model::pandar_xt32}}) {
    SCOPED_TRACE(r.capture);
    const auto packets = packets_of(data_dir / r.capture, r.model);
    ASSERT_FALSE(packets.empty());
    const std::int64_t expected = median_offset(packets);
    const ClockStatus clock = replayed_clock(data_dir / r.capture, r.calibration);
    ASSERT_TRUE(clock.offset_to_host_ns);
    // The replay's median is over the last second's packets (a few per 4 ms): within the
    // recording's own scatter of the median over every packet.
    EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), static_cast<double>(expected), 1e6);
    EXPECT_EQ(clock.source, sim::ClockSource::replayed);
    EXPECT_EQ(clock.stamps, sim::StampClock::sensor);
    EXPECT_EQ(clock.packets_measured, packets.size());
    EXPECT_EQ(clock.verdict, ClockVerdict::error);
    const std::string years = one_decimal(static_cast<double>(-expected) / kYearNs) + " years behind";
    EXPECT_TRUE(says(clock, years)) << "expected \"" << years << "\" in: " << clock.problem;
    EXPECT_TRUE(says(clock, "recording host")) << clock.problem;
  }
}

TEST(HesaiReplayClock, a_looping_replay_is_neither_a_step_nor_time_going_backwards) {
  // Two passes at least: --loop with --duration cannot stop by itself, so a short capture is
  // replayed paced until the stream shows a second pass, then stopped.
  sim::testing::StreamGuard stream(sim::testing::unique_name("hesai_clock_loop"));
  sim::testing::Process replay({replay_tool, (data_dir / "pandar64_dual.pcap").string(), "--stream",
                                stream.name, "--calibration", (data_dir / "pandar64.calibration.csv").string(),
                                "--loop", "--rate", "4", "--quiet"});
  auto reader = sim::testing::wait_for_stream(stream.name);
  ASSERT_TRUE(reader);
  // Until three passes' packets were measured (2400 each); a bound against hangs only.
  std::optional<ClockStatus> clock;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    auto read = reader->clock();
    ASSERT_TRUE(read) << read.error().message;
    if (*read && (*read)->packets_measured > 3 * 2400) {
      clock = **read;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  replay.signal(SIGINT);
  EXPECT_EQ(replay.wait(), 0) << replay.err();
  ASSERT_TRUE(clock) << "the replay measured no three passes";
  EXPECT_EQ(clock->steps, 0u);
  EXPECT_FALSE(says(*clock, "backwards")) << clock->problem;
  EXPECT_TRUE(says(*clock, "years behind")) << clock->problem;
}

TEST(HesaiReplayClock, a_restamped_replay_is_judged_as_host_time) {
  const ClockStatus clock =
      replayed_clock(data_dir / "pandar64_dual.pcap", "pandar64.calibration.csv", {"--restamp"});
  EXPECT_EQ(clock.source, sim::ClockSource::host);
  EXPECT_EQ(clock.stamps, sim::StampClock::host_arrival);
  ASSERT_TRUE(clock.offset_to_host_ns);
  // Stamps moved to the present, measured against the present: off by the pacing only.
  EXPECT_LT(std::abs(*clock.offset_to_host_ns), kS);
  EXPECT_FALSE(says(clock, "years")) << clock.problem;
}

// The recorded capture through the Hesai stream in this process, as sim_replay_pcap feeds it
// (each packet's clock added and ticked), until its first frame: that frame's FrameInfo and the
// stream's clock record then. `base`: replayed, or restamped (--restamp).
struct FirstFrame {
  sim::FrameInfo info;
  ClockStatus clock;
};
FirstFrame first_replayed_frame(sim::timing::ClockBase base) {
  sim::testing::StreamGuard stream(sim::testing::unique_name("hesai_first_frame"));
  sim::hesai::LidarStreamConfig config;
  config.stream = stream.name;
  config.calibration = data_dir / "pandar64.calibration.csv";
  config.assembler.model = sim::hesai::Model::pandar64;
  auto lidar = sim::hesai::LidarStream::create(config);
  EXPECT_TRUE(lidar) << lidar.error().message;
  if (!lidar) return {};
  lidar->clock().set_base(base);
  auto reader = sim::Reader::open(stream.name);
  EXPECT_TRUE(reader) << reader.error().message;
  if (!reader) return {};
  FirstFrame first;
  for (const Packet& p : packets_of(data_dir / "pandar64_dual.pcap", sim::hesai::Model::pandar64)) {
    const sim::hesai::PushResult result = lidar->push(p.bytes, p.capture_ns);
    lidar->clock().add(result.packet_ns, p.capture_ns);
    (void)lidar->tick_clock(p.capture_ns);
    if (!result.frame) continue;
    std::vector<std::byte> buffer(reader->capacity());
    EXPECT_EQ(reader->read(buffer, first.info), sim::ReadStatus::new_frame);
    auto clock = reader->clock();
    EXPECT_TRUE(clock && *clock) << "the first frame was published with no clock record";
    if (clock && *clock) first.clock = **clock;
    return first;
  }
  ADD_FAILURE() << "the capture published no frame";
  return first;
}

TEST(HesaiReplayClock, the_first_frame_of_a_replay_carries_its_stamp_clock_before_the_first_judgement) {
  const FirstFrame replayed = first_replayed_frame(sim::timing::ClockBase::replayed);
  EXPECT_EQ(replayed.info.stamp_clock, sim::StampClock::sensor);
  EXPECT_EQ(replayed.clock.source, sim::ClockSource::replayed);
  // The first frame comes before the first judgement (a quarter second of packets).
  EXPECT_EQ(replayed.clock.verdict, ClockVerdict::unknown) << replayed.clock.problem;
  EXPECT_TRUE(says(replayed.clock, "not judged yet")) << replayed.clock.problem;

  const FirstFrame restamped = first_replayed_frame(sim::timing::ClockBase::restamped);
  EXPECT_EQ(restamped.info.stamp_clock, sim::StampClock::host_arrival);
  EXPECT_EQ(restamped.clock.source, sim::ClockSource::host);
}

struct Rewrite {
  const char* name;
  double seconds;
  std::function<std::int64_t(std::int64_t, std::int64_t)> offset;  // (t, the capture's start)
  ClockVerdict verdict;
  std::vector<std::string> words;
};

TEST(HesaiReplayClock, rewritten_sensor_times_each_get_their_sentence) {
  const std::vector<Rewrite> rewrites{
      {"tai", 3, [](std::int64_t, std::int64_t) { return 37 * kS; }, ClockVerdict::error, {"37 s ahead", "TAI"}},
      {"hour", 3, [](std::int64_t, std::int64_t) { return -3600 * kS; }, ClockVerdict::error, {"1 h behind"}},
      // Up for 3 h at the start: 1970-01-01 03:00 and on (a clock counting from power-on).
      {"uptime", 3, [](std::int64_t, std::int64_t start) { return 3 * 3600 * kS - start; },
       ClockVerdict::error, {"1970", "power-on", "3.0 h"}},
      {"step", 6, [](std::int64_t t, std::int64_t) { return t >= 3 * kS ? 2 * kS : 0; },
       ClockVerdict::error, {"stepped by +2.0 s", "now 2.0 s ahead"}},
      {"drift", 16, [](std::int64_t t, std::int64_t) { return t / 10'000; }, ClockVerdict::warn,
       {"drifts +100 ppm", "free-running"}},
      {"agrees", 3, [](std::int64_t, std::int64_t) { return 500'000; }, ClockVerdict::ok, {}},
  };
  TempDir dir;
  for (const Rewrite& r : rewrites) {
    SCOPED_TRACE(r.name);
    const fs::path capture = rewritten_capture(dir.path, r.name, r.seconds, r.offset);
    const ClockStatus clock = replayed_clock(capture, "pandar64.calibration.csv");
    EXPECT_EQ(clock.verdict, r.verdict) << clock.problem;
    for (const std::string& words : r.words) EXPECT_TRUE(says(clock, words)) << clock.problem;
    if (r.verdict == ClockVerdict::ok) {
      EXPECT_EQ(clock.problem, "");
      ASSERT_TRUE(clock.offset_to_host_ns);
      EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), 500'000.0, 300'000.0);
    }
  }
}

TEST(ReplayClock, velodyne_and_ouster_replays_measure_their_packets_against_the_capture) {
  const fs::path drivers = SIM_DRIVERS_TEST_DIR;
  {
    SCOPED_TRACE("Velodyne VLP-16");
    const fs::path capture = drivers / "velodyne/data/vlp16_dual.pcap";
    std::size_t packets = 0;
    // µs past the hour, in the hour nearest the capture time (as the replay reads it).
    const std::int64_t expected = median_offset(
        capture,
        [](std::span<const std::uint8_t> bytes, std::int64_t capture_ns) -> std::optional<std::int64_t> {
          if (bytes.size() != sim::velodyne::packet_size) return std::nullopt;
          return sim::velodyne::packet_time_ns(
              sim::velodyne::Packet::read_u32(bytes.data() + sim::velodyne::timestamp_offset), capture_ns);
        },
        packets);
    const ClockStatus clock = replayed_clock(capture, drivers / "velodyne/data/VLP16.yaml");
    ASSERT_TRUE(clock.offset_to_host_ns);
    EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), static_cast<double>(expected), 1e6);
    EXPECT_EQ(clock.packets_measured, packets);
    EXPECT_EQ(clock.source, sim::ClockSource::replayed);
    EXPECT_NE(clock.verdict, ClockVerdict::unknown);
  }
  {
    SCOPED_TRACE("Ouster OS-1-32 (legacy)");
    const fs::path capture = drivers / "ouster/data/OS-1-32-G_v2.1.1_1024x10.pcap";
    const fs::path metadata_path = drivers / "ouster/data/OS-1-32-G_v2.1.1_1024x10.json";
    auto metadata = sim::ouster::Metadata::load(metadata_path);
    ASSERT_TRUE(metadata) << metadata.error().message;
    std::size_t packets = 0;
    // The first valid column's time.
    const std::int64_t expected = median_offset(
        capture,
        [&](std::span<const std::uint8_t> bytes, std::int64_t) -> std::optional<std::int64_t> {
          sim::ouster::LidarPacket packet;
          if (sim::ouster::LidarPacket::parse(bytes, metadata->format, packet, metadata->init_id) !=
              sim::ouster::PacketError::none) {
            return std::nullopt;
          }
          for (unsigned c = 0; c < packet.columns(); ++c) {
            if (packet.column(c).valid) return static_cast<std::int64_t>(packet.column(c).timestamp_ns);
          }
          return std::nullopt;
        },
        packets);
    const ClockStatus clock = replayed_clock(capture, metadata_path);
    ASSERT_TRUE(clock.offset_to_host_ns);
    EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), static_cast<double>(expected), 1e6);
    EXPECT_EQ(clock.packets_measured, packets);
    EXPECT_EQ(clock.source, sim::ClockSource::replayed);
    EXPECT_NE(clock.verdict, ClockVerdict::unknown);
  }
}

// What a reader saw of the live driver: its clock record and the newest frame read after the
// record had measured enough packets, with this host's clock when it was read.
struct LiveRun {
  ClockStatus clock;
  std::optional<sim::FrameInfo> frame;
  std::int64_t read_ns = 0;  // CLOCK_REALTIME when `frame` was read
  std::int64_t sent_from_ns = 0;  // CLOCK_REALTIME when the first packet was sent
  std::string err;  // the driver's stderr
};

// The live driver on loopback: each Pandar64 packet goes out with its sensor time set to this
// host's clock at sending plus `offset`, about a thousand a second, until the driver's clock
// record has measured `packets` of them and a frame published after that was read (a bound
// against hangs only).
LiveRun live_run(std::int64_t offset, std::uint64_t packets, const std::vector<std::string>& extra = {}) {
  const auto recorded = packets_of(data_dir / "pandar64_dual.pcap", sim::hesai::Model::pandar64);
  sim::testing::StreamGuard stream(sim::testing::unique_name("hesai_live_clock"));
  std::vector<std::string> argv{SIM_LIDAR_HESAI, "--model", "Pandar64", "--port", "0", "--bind", "127.0.0.1",
                                "--stream", stream.name, "--calibration",
                                (data_dir / "pandar64.calibration.csv").string(), "--status-interval", "0"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  sim::testing::Process driver(argv);
  LiveRun out;
  const auto line = driver.wait_for_line("listening on");
  EXPECT_TRUE(line) << driver.err();
  if (!line) return out;
  auto reader = sim::testing::wait_for_stream(stream.name);
  EXPECT_TRUE(reader);
  if (!reader) return out;

  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(std::stoi(line->substr(line->rfind(':') + 1))));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::optional<ClockStatus> clock;
  std::vector<std::byte> points(reader->capacity());
  out.sent_from_ns = sim::realtime_ns();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  for (std::size_t i = 0; !out.frame && std::chrono::steady_clock::now() < deadline; ++i) {
    std::vector<std::uint8_t> bytes = recorded[i % recorded.size()].bytes;
    write_p64_time(bytes, sim::realtime_ns() + offset);
    ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (i % 50 != 0) continue;
    if (!clock) {
      auto read = reader->clock();
      EXPECT_TRUE(read) << read.error().message;
      if (read && *read && (*read)->packets_measured >= packets) clock = **read;
      sim::FrameInfo before;
      if (clock) (void)reader->read(points, before);  // frames published before: seen
      continue;
    }
    sim::FrameInfo info;
    if (reader->read(points, info) == sim::ReadStatus::new_frame) {
      out.read_ns = sim::realtime_ns();
      out.frame = info;
      auto read = reader->clock();  // the record as it stands with that frame
      if (read && *read) clock = **read;
    }
  }
  ::close(fd);
  driver.signal(SIGINT);
  EXPECT_EQ(driver.wait(), 0) << driver.err();
  out.err = driver.err();
  EXPECT_TRUE(clock) << "the driver measured no " << packets << " packets";
  EXPECT_TRUE(out.frame) << "no frame was read after the clock was judged";
  out.clock = clock.value_or(ClockStatus{});
  return out;
}

ClockStatus live_clock(std::int64_t offset, std::uint64_t packets) { return live_run(offset, packets).clock; }

TEST(LiveClock, the_live_driver_judges_the_same_packets_against_their_arrival) {
  if (g_no_network) GTEST_SKIP() << *g_no_network;
  {
    SCOPED_TRACE("37 s ahead");
    const ClockStatus clock = live_clock(37 * kS, 300);
    ASSERT_TRUE(clock.offset_to_host_ns);
    // Loopback takes microseconds; the sender stamps just before sending.
    EXPECT_NEAR(static_cast<double>(*clock.offset_to_host_ns), 37e9, 5e6);
    EXPECT_EQ(clock.verdict, ClockVerdict::error);
    EXPECT_TRUE(says(clock, "37 s ahead of this host")) << clock.problem;
    EXPECT_TRUE(says(clock, "TAI")) << clock.problem;
    EXPECT_EQ(clock.stamps, sim::StampClock::sensor);
  }
  {
    SCOPED_TRACE("on time");
    const ClockStatus clock = live_clock(0, 300);
    ASSERT_TRUE(clock.offset_to_host_ns);
    EXPECT_LT(std::abs(*clock.offset_to_host_ns), 10 * kMs) << clock.problem;
    EXPECT_FALSE(says(clock, "TAI")) << clock.problem;
    EXPECT_NE(clock.verdict, ClockVerdict::error) << clock.problem;
  }
}

TEST(LiveClock, with_stamp_fallback_host_frames_of_a_clock_in_error_are_stamped_at_their_arrival) {
  if (g_no_network) GTEST_SKIP() << *g_no_network;
  const LiveRun run = live_run(37 * kS, 300, {"--stamp-fallback", "host"});
  ASSERT_TRUE(run.frame);
  EXPECT_EQ(run.frame->stamp_clock, sim::StampClock::host_arrival);
  // The arrival of the frame's first packet on this host: sent after the sending began, read
  // after it arrived, and not the sensor's 37 s ahead.
  EXPECT_EQ(run.frame->stamp_ns, run.frame->receive_ns);
  EXPECT_GE(run.frame->stamp_ns, run.sent_from_ns);
  EXPECT_LE(run.frame->stamp_ns, run.read_ns);
  EXPECT_LT(run.read_ns - run.frame->stamp_ns, 5 * kS) << "a frame spans ~0.6 s of packets here";
  // The check still judges the sensor's own clock, and the record says what the frames are in.
  EXPECT_EQ(run.clock.verdict, ClockVerdict::error);
  ASSERT_TRUE(run.clock.offset_to_host_ns);
  EXPECT_NEAR(static_cast<double>(*run.clock.offset_to_host_ns), 37e9, 5e6);
  EXPECT_TRUE(says(run.clock, "37 s ahead of this host")) << run.clock.problem;
  EXPECT_TRUE(says(run.clock, "host arrival time")) << run.clock.problem;
  EXPECT_EQ(run.clock.stamps, sim::StampClock::host_arrival);
  EXPECT_NE(sim::summary(run.clock).find("host arrival time"), std::string::npos) << sim::summary(run.clock);
  // Told once on stderr, with the reason.
  const auto told = run.err.find("stamps: host arrival time from now on");
  EXPECT_NE(told, std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("stamps: host arrival time from now on", told + 1), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("37 s ahead"), std::string::npos) << run.err;
}

TEST(LiveClock, without_stamp_fallback_frames_keep_the_sensors_stamps) {
  if (g_no_network) GTEST_SKIP() << *g_no_network;
  const LiveRun run = live_run(37 * kS, 300);
  ASSERT_TRUE(run.frame);
  EXPECT_EQ(run.frame->stamp_clock, sim::StampClock::sensor);
  EXPECT_GT(run.frame->stamp_ns - run.read_ns, 30 * kS);  // the sensor's, 37 s ahead
  EXPECT_EQ(run.clock.verdict, ClockVerdict::error);
  EXPECT_EQ(run.clock.stamps, sim::StampClock::sensor);
  EXPECT_FALSE(says(run.clock, "host arrival time")) << run.clock.problem;
  EXPECT_EQ(run.err.find("stamps:"), std::string::npos) << run.err;
}

}  // namespace

int main(int argc, char** argv) {
  g_no_network = sim::testing::enter_private_network(sim::testing::Multicast::off);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
