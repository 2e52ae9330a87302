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
#include <memory>
#include <string>

#include "sim/lidar/udp_receiver.hpp"
#include "sim/ouster/lidar_stream.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

struct NetworkConfig {
  // Where to listen and whom to hear: bind, multicast group, source, receive buffer (per
  // socket), silence timeout. IPv4 (lidar::address_problem(…, IpVersions::v4) checks an address).
  lidar::UdpListen listen{.receive_buffer = 32 << 20};
  std::uint16_t data_port = 7502;  // 0: a free port (read back with data_port())
  std::uint16_t imu_port = 7503;    // 0: a free port
};

// datagrams (lidar and IMU), other_source, oversized (larger than any Ouster packet, cut by the
// buffer) and resumes (packets came back after a silence).
using ReceiveCounters = lidar::ReceiveCounters;
// note: a metadata mismatch, a resume; tick: every tick_period, for a status line.
using ReceiverCallbacks = lidar::ReceiverCallbacks;

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

  std::uint16_t data_port() const noexcept;
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
