// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: an Ouster sensor's lidar and IMU datagrams into a LidarStream, the live end of
// the driver.
//
//   auto receiver = sim::ouster::LiveReceiver::open(network);   // the sockets, nothing else
//   auto stream = sim::ouster::LidarStream::create(config, metadata);
//   receiver->run(*stream, stop_fd, callbacks);                  // until stop_fd is readable
//
// Both sockets take datagrams in recvmmsg batches into 64 KiB buffers (Ouster datagrams are
// 6–33 kB; a bigger buffer lets an oversized one arrive whole and be refused by its size rather
// than cut to a plausible one), with the kernel's arrival stamps (SO_TIMESTAMPNS). The kernel
// reassembles the IPv4 fragments these datagrams travel in.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "sim/ouster/lidar_stream.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

struct NetworkConfig {
  std::string bind = "0.0.0.0";  // IPv4 address to receive on
  std::uint16_t lidar_port = 7502;  // 0: a free port (read back with lidar_port())
  std::uint16_t imu_port = 7503;    // 0: a free port
  std::string multicast_group;      // empty: unicast
  std::string source;               // empty: datagrams from any sender
  int receive_buffer = 32 << 20;    // SO_RCVBUF asked for (SO_RCVBUFFORCE when root)
  std::chrono::nanoseconds silence_timeout = std::chrono::milliseconds(500);
};

// "'x' is not an IPv4 address (e.g. 192.168.1.201)", or "" when it is one.
std::string ipv4_problem(const std::string& address);
std::string multicast_group_problem(const std::string& group);

struct ReceiveCounters {
  std::uint64_t datagrams = 0;
  std::uint64_t other_source = 0;  // from another sender than NetworkConfig::source
  std::uint64_t oversized = 0;     // larger than any Ouster packet (cut by the buffer)
  std::uint64_t resumes = 0;       // packets came back after a silence
};

struct ReceiverCallbacks {
  std::function<void(std::string_view)> note;  // one sentence: a metadata mismatch, a resume
  std::chrono::nanoseconds tick_period{0};
  std::function<void()> tick;
};

class LiveReceiver {
 public:
  static Expected<LiveReceiver> open(const NetworkConfig& network);

  LiveReceiver(LiveReceiver&&) noexcept;
  LiveReceiver& operator=(LiveReceiver&&) noexcept;
  LiveReceiver(const LiveReceiver&) = delete;
  LiveReceiver& operator=(const LiveReceiver&) = delete;
  ~LiveReceiver();

  // Receives into `stream` until `stop_fd` becomes readable (-1: never).
  void run(LidarStream& stream, int stop_fd, const ReceiverCallbacks& callbacks = {});

  std::uint16_t lidar_port() const noexcept;
  std::uint16_t imu_port() const noexcept;
  int receive_buffer() const noexcept;  // SO_RCVBUF granted
  const ReceiveCounters& counters() const noexcept;
  std::int64_t last_packet_ns() const noexcept;  // CLOCK_MONOTONIC; 0 before the first

  struct Impl;

 private:
  explicit LiveReceiver(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::ouster
