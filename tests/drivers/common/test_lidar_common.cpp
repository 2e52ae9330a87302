// SPDX-License-Identifier: Apache-2.0
// sim::lidar_common, what the Hesai, Velodyne and Ouster live ends share: the UDP receiver
// (sender filter, oversized datagrams, ports in use, addresses, silences), the TCP exchange
// with its deadline, the fetched-file cache and the frame publisher.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sim/clock.hpp"
#include "sim/lidar/frame_publisher.hpp"
#include "sim/lidar/live_receiver.hpp"
#include "sim/lidar/tcp_client.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/reader.hpp"
#include "sim_test/network.hpp"
#include "sim_test/streams.hpp"

namespace {

using sim::lidar::IpVersions;
using sim::lidar::UdpListen;
using sim::lidar::UdpPort;
using sim::lidar::UdpReceiver;

std::optional<std::string> g_skip_reason;

// A UDP socket bound to `address` (any 127.x.y.z is the loopback) that sends to 127.0.0.1:port.
class Sender {
 public:
  explicit Sender(const char* address) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in local{};
    local.sin_family = AF_INET;
    ::inet_pton(AF_INET, address, &local.sin_addr);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local), 0) << address;
  }
  ~Sender() { ::close(fd_); }
  void send(std::uint16_t port, std::size_t size, std::uint8_t fill) const {
    const std::vector<std::uint8_t> payload(size, fill);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    ::inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    EXPECT_EQ(::sendto(fd_, payload.data(), payload.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to),
              static_cast<ssize_t>(size));
  }

 private:
  int fd_;
};

// Keeps what the receiver hands over; ends the run after `wanted` datagrams.
struct Collector final : sim::lidar::DatagramHandler {
  explicit Collector(std::size_t w) : wanted(w) {}
  bool on_datagram(const sim::lidar::Datagram& d) override {
    payloads.emplace_back(d.payload.begin(), d.payload.end());
    truncated.push_back(d.truncated);
    senders.push_back(sim::lidar::address_text(*d.sender));
    return payloads.size() < wanted;
  }
  std::size_t wanted;
  std::vector<std::vector<std::uint8_t>> payloads;
  std::vector<bool> truncated;
  std::vector<std::string> senders;
};

// Runs the receiver until the collector has what it wants, or (a receiver that hears nothing)
// until `bound` has passed: the bound ends a broken run, it asserts nothing.
void run_at_most(UdpReceiver& receiver, Collector& collector, std::chrono::seconds bound = std::chrono::seconds(20)) {
  const int stop = ::eventfd(0, EFD_CLOEXEC);
  const auto until = std::chrono::steady_clock::now() + bound;
  sim::lidar::ReceiverCallbacks callbacks;
  callbacks.tick_period = std::chrono::milliseconds(50);
  callbacks.tick = [&] {
    if (std::chrono::steady_clock::now() < until) return;
    const std::uint64_t one = 1;
    EXPECT_EQ(::write(stop, &one, sizeof one), 8);
  };
  receiver.run(stop, collector, callbacks);
  ::close(stop);
}

// Sends to a multicast group through loopback (the private network routes 224.0.0.0/4 there).
void send_to_group(const char* group, std::uint16_t port, std::size_t count, std::uint8_t fill) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  in_addr lo{};
  ::inet_pton(AF_INET, "127.0.0.1", &lo);
  ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &lo, sizeof lo);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  ::inet_pton(AF_INET, group, &to.sin_addr);
  const std::vector<std::uint8_t> payload(100, fill);
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(::sendto(fd, payload.data(), payload.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to), 100);
  }
  ::close(fd);
}

UdpListen loopback() {
  UdpListen listen;
  listen.bind = "127.0.0.1";
  listen.receive_buffer = 1 << 20;
  return listen;
}

// A family as LiveReceiver<Route> sees it: a stream that keeps what each push took, and a route
// with a data and a position socket whose oversized datagrams are refused.
struct FakeResult {
  std::optional<std::int64_t> packet_ns;
};
struct FakeStream {
  FakeResult push(std::span<const std::uint8_t> payload, std::int64_t /*arrival_ns*/) noexcept {
    data.push_back(payload[0]);
    return {};
  }
  void reset() noexcept { ++resets; }
  sim::timing::ClockReporter& clock() noexcept { return reporter; }
  std::int64_t stamp_offset() const noexcept { return 0; }
  std::optional<sim::ClockStatus> tick_clock(std::int64_t /*now*/, bool /*at_once*/ = false) { return std::nullopt; }

  std::vector<std::uint8_t> data;      // each data push's first byte
  std::vector<std::uint8_t> position;  // each position push's first byte
  int resets = 0;
  sim::timing::ClockReporter reporter;
};
struct FakeRoute {
  using Stream = FakeStream;
  static constexpr std::size_t datagram_size = 2048;
  static constexpr std::size_t batch_size = 4;
  static constexpr bool refuse_truncated = true;
  std::vector<sim::lidar::RoutedPort> ports() const {
    return {{sim::lidar::PacketKind::data, {0, "UDP", "--port"}},
            {sim::lidar::PacketKind::position, {0, "the position", "--position-port"}}};
  }
  sim::lidar::PacketKind operator()(std::uint16_t /*port*/, std::span<const std::uint8_t> /*payload*/) const noexcept {
    return sim::lidar::PacketKind::data;
  }
  static bool push_other(FakeStream& stream, sim::lidar::PacketKind kind, std::span<const std::uint8_t> payload,
                         std::int64_t /*arrival_ns*/) noexcept {
    if (kind == sim::lidar::PacketKind::position) stream.position.push_back(payload[0]);
    return true;
  }
};

TEST(LiveReceiver, EachSocketFeedsItsPushAndAnOversizedDatagramIsCountedNotPushed) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  auto receiver = sim::lidar::LiveReceiver<FakeRoute>::open(loopback(), FakeRoute{});
  ASSERT_TRUE(receiver) << receiver.error().message;
  ASSERT_NE(receiver->data_port(), 0);
  ASSERT_NE(receiver->position_port(), 0);
  EXPECT_NE(receiver->data_port(), receiver->position_port());
  EXPECT_EQ(receiver->imu_port(), 0);

  const Sender sensor("127.0.0.1");
  for (std::uint8_t fill = 1; fill <= 6; ++fill) sensor.send(receiver->data_port(), 100, fill);  // more than a batch
  sensor.send(receiver->position_port(), 512, 7);
  sensor.send(receiver->data_port(), 3000, 9);  // larger than the buffer
  sensor.send(receiver->position_port(), 512, 8);

  FakeStream stream;
  const int stop = ::eventfd(0, EFD_CLOEXEC);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  sim::lidar::ReceiverCallbacks callbacks;
  callbacks.tick_period = std::chrono::milliseconds(20);
  callbacks.tick = [&] {
    const bool all = stream.data.size() == 6 && stream.position.size() == 2 && receiver->counters().oversized == 1;
    if (!all && std::chrono::steady_clock::now() < until) return;
    const std::uint64_t one = 1;
    EXPECT_EQ(::write(stop, &one, sizeof one), 8);
  };
  receiver->run(stream, stop, callbacks);
  ::close(stop);

  EXPECT_EQ(stream.data, (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(stream.position, (std::vector<std::uint8_t>{7, 8}));
  EXPECT_EQ(receiver->counters().oversized, 1U);
  EXPECT_EQ(stream.resets, 0);
  EXPECT_NE(receiver->last_packet_ns(), 0);
  EXPECT_EQ(receiver->stream(), nullptr);  // outside run(stream, …)
}

TEST(UdpReceiver, DatagramsFromAnotherSenderAreCountedAndNotHandled) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  UdpListen listen = loopback();
  listen.source = "127.0.0.2";
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto receiver = UdpReceiver::open(listen, ports, 2048);
  ASSERT_TRUE(receiver) << receiver.error().message;
  Sender other("127.0.0.3");
  Sender sensor("127.0.0.2");
  other.send(receiver->port(), 100, 0xAA);
  sensor.send(receiver->port(), 120, 0x55);  // queued before run(): one take sees both

  Collector collector(1);
  receiver->run(-1, collector);
  ASSERT_EQ(collector.payloads.size(), 1u);
  EXPECT_EQ(collector.payloads[0], std::vector<std::uint8_t>(120, 0x55));
  EXPECT_EQ(collector.senders[0], "127.0.0.2");
  EXPECT_EQ(receiver->counters().datagrams, 2u);
  EXPECT_EQ(receiver->counters().other_source, 1u);
}

TEST(UdpReceiver, ThreeSensorsMulticastingToThreeGroupsOnOnePortAreEachHeardOnlyByTheirOwnDriver) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::array<const char*, 3> groups{"239.1.1.1", "239.1.1.2", "239.1.1.3"};
  std::vector<UdpReceiver> receivers;
  std::uint16_t port = 0;  // the first receiver's free port; the others share it
  for (const char* group : groups) {
    UdpListen listen;
    listen.multicast_group = group;
    listen.receive_buffer = 1 << 20;
    const std::array ports{UdpPort{port, "UDP", "--port"}};
    auto receiver = UdpReceiver::open(listen, ports, 2048);
    ASSERT_TRUE(receiver) << receiver.error().message;
    port = receiver->port();
    receivers.push_back(std::move(*receiver));
  }
  // Every datagram is queued before any receiver runs: one that got another group's datagrams
  // takes them in its first batch and counts them.
  for (std::size_t g = 0; g < groups.size(); ++g) send_to_group(groups[g], port, 3 + g, static_cast<std::uint8_t>(g + 1));
  for (std::size_t g = 0; g < groups.size(); ++g) {
    Collector collector(3 + g);
    run_at_most(receivers[g], collector);
    ASSERT_EQ(collector.payloads.size(), 3 + g) << groups[g];
    for (const auto& payload : collector.payloads) EXPECT_EQ(payload[0], g + 1) << groups[g];
    EXPECT_EQ(receivers[g].counters().datagrams, 3 + g) << groups[g] << " heard another group";
  }
}

TEST(UdpReceiver, ABindAddressWithAMulticastGroupIsTheInterfaceTheGroupIsJoinedOn) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  UdpListen listen = loopback();
  listen.multicast_group = "239.1.1.4";
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto receiver = UdpReceiver::open(listen, ports, 2048);
  ASSERT_TRUE(receiver) << receiver.error().message;
  send_to_group("239.1.1.4", receiver->port(), 5, 7);
  Collector collector(5);
  run_at_most(*receiver, collector);
  EXPECT_EQ(collector.payloads.size(), 5u) << "a socket bound to 127.0.0.1 never matches a group destination";

  listen.bind = "192.0.2.1";  // no interface holds it
  auto refused = UdpReceiver::open(listen, ports, 2048);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("on the interface of 192.0.2.1"), std::string::npos)
      << refused.error().message;
}

TEST(UdpReceiver, TwoAndThreeSensorsOnOnePortAreCountedAndWarnedOfOnce) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto receiver = UdpReceiver::open(loopback(), ports, 2048);
  ASSERT_TRUE(receiver) << receiver.error().message;
  Sender first("127.0.0.2");
  Sender second("127.0.0.3");
  Sender third("127.0.0.4");
  for (int i = 0; i < 2; ++i) {
    first.send(receiver->port(), 100, 1);
    second.send(receiver->port(), 100, 2);
    third.send(receiver->port(), 100, 3);
  }
  std::vector<std::string> notes;
  sim::lidar::ReceiverCallbacks callbacks;
  callbacks.note = [&](std::string_view note) { notes.emplace_back(note); };
  Collector collector(6);
  receiver->run(-1, collector, callbacks);
  ASSERT_EQ(collector.payloads.size(), 6u) << "without --source every sender is still handled";
  EXPECT_EQ(receiver->counters().other_senders, 4u);
  EXPECT_EQ(receiver->counters().other_source, 0u);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("127.0.0.3"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("127.0.0.2"), std::string::npos) << notes[0];
  EXPECT_NE(sim::lidar::describe_problems(receiver->counters()).find("other-senders 4"), std::string::npos);
}

TEST(UdpReceiver, ADatagramLargerThanTheBufferArrivesMarkedTruncated) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto receiver = UdpReceiver::open(loopback(), ports, 64);
  ASSERT_TRUE(receiver) << receiver.error().message;
  Sender sender("127.0.0.1");
  sender.send(receiver->port(), 100, 1);
  sender.send(receiver->port(), 64, 2);

  Collector collector(2);
  receiver->run(-1, collector);
  ASSERT_EQ(collector.payloads.size(), 2u);
  EXPECT_TRUE(collector.truncated[0]);
  EXPECT_EQ(collector.payloads[0].size(), 64u);
  EXPECT_FALSE(collector.truncated[1]);
  EXPECT_EQ(collector.payloads[1], std::vector<std::uint8_t>(64, 2));
}

TEST(UdpReceiver, EachSocketsDatagramsCarryItsIndex) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::array ports{UdpPort{0, "the lidar", "--lidar-port"}, UdpPort{0, "the IMU", "--imu-port"}};
  auto receiver = UdpReceiver::open(loopback(), ports, 2048);
  ASSERT_TRUE(receiver) << receiver.error().message;
  ASSERT_NE(receiver->port(0), receiver->port(1));
  EXPECT_EQ(receiver->port(2), 0) << "no third socket";
  Sender sender("127.0.0.1");
  sender.send(receiver->port(1), 48, 7);

  struct Index final : sim::lidar::DatagramHandler {
    bool on_datagram(const sim::lidar::Datagram& d) override {
      socket = d.socket;
      return false;
    }
    std::size_t socket = 99;
  } index;
  receiver->run(-1, index);
  EXPECT_EQ(index.socket, 1u);
}

TEST(UdpReceiver, APortInUseIsOneSentenceNamingTheOptionThatChoosesIt) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const std::array first_ports{UdpPort{0, "UDP", "--port"}};
  auto first = UdpReceiver::open(loopback(), first_ports, 2048);
  ASSERT_TRUE(first) << first.error().message;
  const std::array ports{UdpPort{first->port(), "the IMU", "--imu-port"}};
  auto second = UdpReceiver::open(loopback(), ports, 2048);
  ASSERT_FALSE(second);
  EXPECT_EQ(second.error().code, sim::ErrorCode::system_error);
  EXPECT_EQ(second.error().message, "the IMU port " + std::to_string(first->port()) +
                                        " on 127.0.0.1 is already in use by another process (another "
                                        "driver?); stop it or choose another --imu-port.");
}

TEST(UdpReceiver, ALinkLocalIpv6AddressWithItsZoneIsAnAddressWhereIpv6IsAccepted) {
  EXPECT_EQ(sim::lidar::address_problem("fe80::1%lo", IpVersions::v4_and_v6), "");
  EXPECT_EQ(sim::lidar::address_problem("fe80::1%1", IpVersions::v4_and_v6), "");
  EXPECT_NE(sim::lidar::address_problem("fe80::1%no_such_interface", IpVersions::v4_and_v6), "");
  EXPECT_NE(sim::lidar::address_problem("fe80::1%lo", IpVersions::v4), "");
}

TEST(UdpReceiver, AnAddressThatIsNotOneIsRefusedBeforeAnySocketIsOpened) {
  UdpListen listen = loopback();
  listen.source = "192.168.1";
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto refused = UdpReceiver::open(listen, ports, 2048);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, sim::ErrorCode::invalid_argument);
  EXPECT_EQ(refused.error().message,
            "the source address '192.168.1' is not an IPv4 address (e.g. 192.168.1.201); give the "
            "sensor's address.");
  EXPECT_EQ(sim::lidar::address_problem("::1", IpVersions::v4), "'::1' is not an IPv4 address (e.g. 192.168.1.201)");
  EXPECT_EQ(sim::lidar::address_problem("::1", IpVersions::v4_and_v6), "");
  EXPECT_EQ(sim::lidar::multicast_group_problem("239.255.0.1", IpVersions::v4), "");
  EXPECT_NE(sim::lidar::multicast_group_problem("192.168.1.201", IpVersions::v4), "");
  EXPECT_EQ(sim::lidar::multicast_group_problem("ff02::1", IpVersions::v4_and_v6), "");
}

TEST(UdpReceiver, OnlyAGapLongerThanTheSilenceTimeoutIsAResume) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  UdpListen listen = loopback();
  listen.silence_timeout = std::chrono::milliseconds(500);
  const std::array ports{UdpPort{0, "UDP", "--port"}};
  auto receiver = UdpReceiver::open(listen, ports, 2048);
  ASSERT_TRUE(receiver) << receiver.error().message;
  constexpr std::int64_t second = 1'000'000'000;
  EXPECT_FALSE(receiver->resumed_after_silence(10 * second));               // the first packet
  EXPECT_FALSE(receiver->resumed_after_silence(10 * second + second / 2));  // exactly the timeout
  EXPECT_TRUE(receiver->resumed_after_silence(12 * second));
  EXPECT_FALSE(receiver->resumed_after_silence(12 * second + 1000));
  EXPECT_EQ(receiver->counters().resumes, 1u);
}

TEST(TcpConnection, ARefusedConnectionIsOneSentenceNamingTheSensorAndTheService) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  // A port nobody listens on: bound once, then closed.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local), 0);
  socklen_t length = sizeof local;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length);
  ::close(fd);
  const std::uint16_t port = ntohs(local.sin_port);

  auto refused = sim::lidar::TcpConnection::connect({"127.0.0.1", port, std::chrono::milliseconds(2000), "PTC"});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().message.rfind("sensor 127.0.0.1:" + std::to_string(port) + " refused the PTC connection (", 0),
            0u)
      << refused.error().message;
  // A name that never resolves (.invalid, RFC 6761): one sentence naming it and the option.
  auto unknown = sim::lidar::TcpConnection::connect({"sensor.invalid", port, std::chrono::milliseconds(2000), "HTTP"});
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("'sensor.invalid' (--sensor-ip)"), std::string::npos) << unknown.error().message;
}

TEST(TcpConnection, AHostIsAnAddressOrAHostNameAndNothingElse) {
  for (const char* good : {"192.168.1.201", "fe80::1", "os-122.local", "localhost", "sensor"}) {
    EXPECT_EQ(sim::lidar::host_problem(good), "") << good;
  }
  for (const char* bad : {"", "os 122", "-x", "a/b", "http://sensor"}) {
    EXPECT_NE(sim::lidar::host_problem(bad), "") << bad;
  }
}

// Ouster sensors are reached by name (os-<serial>.local) as often as by address: a name is
// resolved (here from /etc/hosts) within the connection's timeout.
TEST(TcpConnection, ASensorNameIsResolvedAndConnected) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(listener, reinterpret_cast<const sockaddr*>(&local), sizeof local), 0);
  ASSERT_EQ(::listen(listener, 1), 0);
  socklen_t length = sizeof local;
  ::getsockname(listener, reinterpret_cast<sockaddr*>(&local), &length);
  auto connection = sim::lidar::TcpConnection::connect(
      {"localhost", ntohs(local.sin_port), std::chrono::milliseconds(20000), "HTTP"});
  ASSERT_TRUE(connection) << connection.error().message;
  const int accepted = ::accept(listener, nullptr, nullptr);
  EXPECT_GE(accepted, 0);
  const std::array<std::uint8_t, 4> request{'G', 'E', 'T', ' '};
  EXPECT_EQ(connection->send_all(request), sim::lidar::TcpIo::done);
  std::array<std::uint8_t, 4> got{};
  EXPECT_EQ(::recv(accepted, got.data(), got.size(), MSG_WAITALL), 4);
  EXPECT_EQ(got, request);
  ::close(accepted);
  ::close(listener);
}

TEST(TcpConnection, ASensorThatAcceptsButNeverAnswersEndsTheReadAtTheDeadline) {
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
  // The kernel accepts for a listening socket; nobody ever writes.
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(listener, reinterpret_cast<const sockaddr*>(&local), sizeof local), 0);
  ASSERT_EQ(::listen(listener, 1), 0);
  socklen_t length = sizeof local;
  ::getsockname(listener, reinterpret_cast<sockaddr*>(&local), &length);

  auto connection = sim::lidar::TcpConnection::connect(
      {"127.0.0.1", ntohs(local.sin_port), std::chrono::milliseconds(200), "HTTP"});
  ASSERT_TRUE(connection) << connection.error().message;
  EXPECT_EQ(connection->within(), "within 0.2 s");
  const std::array<std::uint8_t, 4> request{'G', 'E', 'T', ' '};
  EXPECT_EQ(connection->send_all(request), sim::lidar::TcpIo::done);
  std::array<std::uint8_t, 64> buffer{};
  EXPECT_EQ(connection->read_some(buffer).status, sim::lidar::TcpIo::timed_out);
  ::close(listener);
}

TEST(SensorCache, AFileIsWrittenWholeAndAnUnwritablePlaceIsRefused) {
  const auto folder = std::filesystem::temp_directory_path() / ("sim_lidar_common_" + std::to_string(::getpid()));
  const auto file = folder / "sub" / "sensor.json";
  ASSERT_TRUE(sim::lidar::write_atomically(file, "{\"a\": 1}"));
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "{\"a\": 1}");
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".part"));
  EXPECT_FALSE(sim::lidar::write_atomically("/proc/sim-cannot-write/sensor.json", "x"));
  std::filesystem::remove_all(folder);
  EXPECT_EQ(sim::lidar::default_cache_path("ouster-1.2.3.4.json").filename(), "ouster-1.2.3.4.json");
}

TEST(FramePublisher, AFrameIsPublishedWithTheStampOffsetAndCounted) {
  const std::string name = sim::testing::unique_name("lidar_common");
  sim::testing::StreamGuard guard(name);
  struct Config {
    std::string stream;
    bool checksum = false;
    bool lock_memory = false;
    std::chrono::milliseconds heartbeat_period{0};
  } config{.stream = name};
  auto writer = sim::Writer::create(sim::lidar::point_stream_spec(config, 16));
  ASSERT_TRUE(writer) << writer.error().message;
  sim::lidar::PublishCounters counters;
  sim::lidar::FramePublisher frames(std::move(writer.value()), counters);
  ASSERT_EQ(frames.slot().size(), 16u);
  EXPECT_EQ(frames.max_points(), 16u);
  frames.slot()[0].x = 1.5F;
  frames.set_stamp_offset(1000);
  const auto next = frames.publish(3, 5000, 7000, /*whole=*/false);
  EXPECT_EQ(next.size(), 16u);

  auto reader = sim::Reader::open(name);
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.size, 3 * sizeof(sim::LidarPoint));
  EXPECT_EQ(info.stamp_ns, 6000);
  sim::LidarPoint first;
  std::memcpy(&first, buffer.data(), sizeof first);
  EXPECT_EQ(first.x, 1.5F);
  EXPECT_EQ(counters.frames, 1u);
  EXPECT_EQ(counters.points, 3u);
  EXPECT_EQ(counters.partial_frames, 1u);
  EXPECT_EQ(counters.failed, 0u);
  EXPECT_EQ(frames.last_points(), 3u);

  // A corrupt sensor clock near the limit plus a replay's offset: the stamp is held at the
  // limit (an overflow here was undefined behaviour).
  frames.set_stamp_offset(INT64_MAX - 10);
  frames.publish(1, 5000, 7000, /*whole=*/true);
  ASSERT_EQ(reader->read(buffer, info), sim::ReadStatus::new_frame);
  EXPECT_EQ(info.stamp_ns, INT64_MAX);
}

TEST(Stamps, SumsAndDifferencesOfNanosecondsStopAtTheLimitsInsteadOfOverflowing) {
  EXPECT_EQ(sim::saturating_add_ns(5, -7), -2);
  EXPECT_EQ(sim::saturating_add_ns(INT64_MAX - 1, 5), INT64_MAX);
  EXPECT_EQ(sim::saturating_add_ns(INT64_MIN + 1, -5), INT64_MIN);
  EXPECT_EQ(sim::saturating_sub_ns(5, 7), -2);
  EXPECT_EQ(sim::saturating_sub_ns(1'700'000'000'000'000'000, INT64_MIN), INT64_MAX);
  EXPECT_EQ(sim::saturating_sub_ns(-5, INT64_MAX), INT64_MIN);
}

}  // namespace

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::on);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
