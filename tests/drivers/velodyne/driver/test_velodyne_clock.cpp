// SPDX-License-Identifier: Apache-2.0
// A Velodyne's clock as data: a sensor stand-in sends position packets (port 8308) over loopback
// in a private network namespace to the live receiver, and every PPS state it reports reaches
// the receiver's clock accessor (what the clock reporter calls once a second to write the
// stream's clock record) and, while data packets flow, the stream's clock record a reader sees;
// hostile position packets give a warning, never a crash or a lock.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "../packet_builder.hpp"
#include "sim/sim.hpp"
#include "sim/velodyne/live_receiver.hpp"
#include "sim_test/network.hpp"

namespace {

using namespace std::chrono_literals;

std::optional<std::string> g_skip_reason;
const std::string calibration = std::string(VELODYNE_TEST_DATA) + "/VLP16.yaml";

void send_to(std::uint16_t port, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  ::close(fd);
}

// The live receiver of a VLP-16 on 127.0.0.1 (free ports), publishing to a stream of its own,
// run on a thread until the fixture ends.
class VelodyneClock : public ::testing::Test {
 protected:
  void SetUp() override {
    if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
    stream = "/test_velodyne_clock_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    sim::velodyne::NetworkConfig network;
    network.listen.bind = "127.0.0.1";
    network.data_port = 0;
    network.position_port = 0;
    auto opened = sim::velodyne::LiveReceiver::open(network);
    ASSERT_TRUE(opened) << opened.error().message;
    receiver.emplace(std::move(opened.value()));
    sim::velodyne::LidarStreamConfig config;
    config.stream = stream;
    config.calibration = calibration;
    config.assembler.model = sim::velodyne::Model::vlp16;
    config.sensor = sim::SensorInfo{};
    config.sensor->frame_id = "velodyne_top";
    auto published = receiver->publish_to(config, sim::velodyne::Model::vlp16);
    ASSERT_TRUE(published) << published.error().message;
    stop_fd = ::eventfd(0, EFD_CLOEXEC);
    ASSERT_GE(stop_fd, 0);
    thread = std::thread([this] { result = receiver->run(stop_fd); });
  }

  void TearDown() override {
    if (thread.joinable()) {
      const std::uint64_t one = 1;
      EXPECT_EQ(::write(stop_fd, &one, sizeof one), static_cast<ssize_t>(sizeof one));
      thread.join();
      EXPECT_TRUE(result) << result.error().message;
    }
    if (stop_fd >= 0) ::close(stop_fd);
    receiver.reset();
    (void)sim::destroy(stream, true);
  }

  // Sends `packet` to the position port until `clock` satisfies `reached` (a datagram on
  // loopback is not lost, but nothing is assumed of when the receiver's thread takes it);
  // false after a generous bound.
  bool send_until(const std::vector<std::uint8_t>& packet, const std::function<sim::ClockStatus()>& clock,
                  const std::function<bool(const sim::ClockStatus&)>& reached) {
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (std::chrono::steady_clock::now() < deadline) {
      send_to(receiver->position_port(), packet);
      for (int i = 0; i < 100; ++i) {
        if (reached(clock())) return true;
        std::this_thread::sleep_for(2ms);
      }
    }
    return reached(clock());
  }

  static inline int counter = 0;
  std::string stream;
  std::optional<sim::velodyne::LiveReceiver> receiver;
  int stop_fd = -1;
  std::thread thread;
  sim::Expected<void> result{};
};

const std::string gprmc = velodyne_test::nmea("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230326,003.1,W");
const std::uint32_t at_35_20 = (35 * 60 + 20) * 1'000'000U;  // µs past the hour, a second after the sentence

TEST_F(VelodyneClock, EveryPpsStateTheSensorReportsReachesTheClockAccessor) {
  // What a clock reporter takes: a function it may call from its own thread.
  const std::function<sim::ClockStatus()> clock = receiver->reported_clock();
  const sim::ClockStatus before = clock();
  EXPECT_EQ(before.source, sim::ClockSource::unknown);
  EXPECT_EQ(before.reported_ns, 0);
  EXPECT_EQ(before.stamps, sim::StampClock::sensor);

  struct Step {
    std::uint8_t pps;
    sim::ClockState state;
  };
  // Every transition a sensor goes through, and back: each one must show.
  const std::vector<Step> steps{{0, sim::ClockState::free_running}, {1, sim::ClockState::acquiring},
                                {2, sim::ClockState::locked},       {3, sim::ClockState::holdover},
                                {1, sim::ClockState::acquiring},    {2, sim::ClockState::locked},
                                {0, sim::ClockState::free_running}};
  std::int64_t last_reported = 0;
  for (const Step& step : steps) {
    const auto packet = velodyne_test::position_packet(at_35_20, step.pps, gprmc);
    ASSERT_TRUE(send_until(packet, clock, [&](const sim::ClockStatus& c) { return c.state == step.state; }))
        << "PPS " << int{step.pps} << " never reached the accessor: " << clock().problem;
    const sim::ClockStatus now = clock();
    EXPECT_EQ(now.source, sim::ClockSource::pps_nmea);
    EXPECT_EQ(now.stamps, sim::StampClock::sensor);
    EXPECT_GE(now.reported_ns, last_reported);  // the packet's arrival on this host
    EXPECT_GT(now.reported_ns, 0);
    EXPECT_EQ(now.verdict == sim::ClockVerdict::warn, step.state != sim::ClockState::locked) << now.problem;
    last_reported = now.reported_ns;
  }
  EXPECT_GE(receiver->stream()->published().position_packets, steps.size());
  EXPECT_EQ(receiver->stream()->time_sync().text, "PPS absent, GPRMC valid");
}

TEST_F(VelodyneClock, HostilePositionPacketsGiveAWarningAndTheReceiverGoesOn) {
  const std::function<sim::ClockStatus()> clock = receiver->reported_clock();
  ASSERT_TRUE(send_until(velodyne_test::position_packet(at_35_20, 2, gprmc), clock,
                         [](const sim::ClockStatus& c) { return c.state == sim::ClockState::locked; }));

  // A PPS byte out of range with bytes that are no NMEA: not locked, a warning that says why.
  std::vector<std::uint8_t> hostile(512);
  for (std::size_t i = 0; i < hostile.size(); ++i) hostile[i] = static_cast<std::uint8_t>(i * 131 + 7);
  hostile[202] = 0xCA;
  ASSERT_TRUE(send_until(hostile, clock, [](const sim::ClockStatus& c) { return c.state == sim::ClockState::unknown; }));
  sim::ClockStatus now = clock();
  EXPECT_EQ(now.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(now.problem.find("PPS byte is 202"), std::string::npos) << now.problem;

  // PPS locked with a garbage sentence, then a datagram that is no position packet at all.
  ASSERT_TRUE(send_until(velodyne_test::position_packet(at_35_20, 2, "$GPRMC,\x01\xff garbage*ZZ"), clock,
                         [](const sim::ClockStatus& c) { return c.state == sim::ClockState::locked; }));
  now = clock();
  EXPECT_EQ(now.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(now.problem.find("NMEA sentence is unreadable"), std::string::npos) << now.problem;
  send_to(receiver->position_port(), std::vector<std::uint8_t>(1500, 0xFF));

  // The receiver still takes good packets: the sensor's lock shows again, without a warning.
  ASSERT_TRUE(send_until(velodyne_test::position_packet(at_35_20, 2, gprmc), clock, [](const sim::ClockStatus& c) {
    return c.state == sim::ClockState::locked && c.verdict == sim::ClockVerdict::unknown;
  })) << clock().problem;
  EXPECT_GE(receiver->stream()->published().position_malformed, 1U);
}

// What a reader of the stream sees: the clock record, which the clock check writes about once a
// second while data packets arrive, follows every PPS state the position packets report.
TEST_F(VelodyneClock, EveryPpsStateReachesTheStreamsClockRecord) {
  // The sensor's data packets, stamped with this host's µs past the hour, one a millisecond.
  std::atomic<bool> feeding{true};
  std::thread feeder([&] {
    velodyne_test::DataPacket packet;
    std::uint16_t azimuth = 0;
    while (feeding.load()) {
      for (auto& block : packet.blocks) {
        block.azimuth = azimuth;
        azimuth = static_cast<std::uint16_t>((azimuth + 20) % 36000);
      }
      packet.timestamp_us = static_cast<std::uint32_t>((sim::realtime_ns() / 1000) % 3'600'000'000);
      send_to(receiver->data_port(), packet.bytes());
      std::this_thread::sleep_for(1ms);
    }
  });
  auto reader = sim::Reader::open(stream);
  ASSERT_TRUE(reader) << reader.error().message;
  const std::function<sim::ClockStatus()> record = [&reader] {
    auto clock = reader->clock();
    return clock && clock->has_value() ? **clock : sim::ClockStatus{};
  };
  struct Step {
    std::uint8_t pps;
    sim::ClockState state;
  };
  for (const Step step : {Step{1, sim::ClockState::acquiring}, Step{2, sim::ClockState::locked},
                          Step{0, sim::ClockState::free_running}, Step{3, sim::ClockState::holdover},
                          Step{2, sim::ClockState::locked}}) {
    const auto packet = velodyne_test::position_packet(at_35_20, step.pps, gprmc);
    EXPECT_TRUE(send_until(packet, record, [&](const sim::ClockStatus& c) { return c.state == step.state; }))
        << "PPS " << int{step.pps} << " never reached the stream's record: " << sim::summary(record());
    EXPECT_EQ(record().source, sim::ClockSource::pps_nmea);
    EXPECT_EQ(record().stamps, sim::StampClock::sensor);
  }
  feeding.store(false);
  feeder.join();
}

// The route the live receiver and the replay share: by port when the datagram names one of the
// route's ports, by size when it names neither (a capture recorded on other ports).
TEST(VelodyneRoute, DataPacketsGoToPushAndPositionPacketsToPushPositionByPortOrBySize) {
  using sim::lidar::PacketKind;
  const sim::velodyne::Route route;
  const std::vector<std::uint8_t> data(sim::velodyne::packet_size, 0);
  const std::vector<std::uint8_t> position(512, 0);
  EXPECT_EQ(route(2368, data), PacketKind::data);
  EXPECT_EQ(route(8308, position), PacketKind::position);
  EXPECT_EQ(route(8308, data), PacketKind::position);  // the port tells first
  EXPECT_EQ(route(9999, data), PacketKind::data);
  EXPECT_EQ(route(9999, position), PacketKind::position);
  const auto ports = route.ports();
  ASSERT_EQ(ports.size(), 2U);
  EXPECT_EQ(ports[0].kind, PacketKind::data);
  EXPECT_EQ(ports[1].kind, PacketKind::position);
  const sim::velodyne::Route data_only{.position_port = std::nullopt};
  EXPECT_EQ(data_only.ports().size(), 1U);
}

}  // namespace

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::off);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
