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
#include <utility>

#include "sim/lidar/live_receiver.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/ouster/lidar_stream.hpp"
#include "sim/ouster/route.hpp"
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

// lidar::LiveReceiver<Route>: run(stream, stop_fd, callbacks) into a stream made from the
// metadata, data_port(), imu_port(), receive_buffer(), counters(), last_packet_ns()
// (CLOCK_MONOTONIC of the last lidar packet; 0 before the first). A lidar packet that does not
// fit the metadata is noted once (LidarStream::mismatch_problem).
class LiveReceiver final : public lidar::LiveReceiver<Route> {
 public:
  static Expected<LiveReceiver> open(const NetworkConfig& network);

 private:
  explicit LiveReceiver(lidar::LiveReceiver<Route>&& opened) noexcept : lidar::LiveReceiver<Route>(std::move(opened)) {}
};

}  // namespace sim::ouster
