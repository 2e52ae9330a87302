// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: a Velodyne sensor's UDP packets into a LidarStream, the live end of the driver.
//
//   auto receiver = sim::velodyne::LiveReceiver::open({.data_port = 2368});  // sockets only
//   receiver->publish_to(stream_config, model);     // model nullopt: from the first packet
//   receiver->run(stop_fd, {.tick = print_status}); // until stop_fd is readable
//
// Two sockets: data packets (2368) and position packets (8308, the GPRMC/PPS state). Datagrams
// are taken in recvmmsg batches with the kernel's arrival stamps (SO_TIMESTAMPNS). A gap
// between arrival stamps longer than the silence timeout means the sensor stopped: the
// revolution in progress is dropped and the next packet starts anew. IPv4.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "sim/lidar/live_receiver.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"
#include "sim/velodyne/lidar_stream.hpp"
#include "sim/velodyne/route.hpp"

namespace sim::velodyne {

struct NetworkConfig {
  // Where to listen and whom to hear: bind, multicast group, source, receive buffer, silence
  // timeout. IPv4 (lidar::address_problem(…, IpVersions::v4) checks an address).
  lidar::UdpListen listen;
  std::uint16_t data_port = default_data_port;  // 0: a free port, read back with data_port()
  std::optional<std::uint16_t> position_port = default_position_port;  // nullopt: not listened to
};

// datagrams (data and position), other_source, unrecognised (not a Velodyne data packet,
// before the model was known) and resumes (packets came back after a silence).
using ReceiveCounters = lidar::ReceiveCounters;
// note: the model detected, packets resumed…; tick: every tick_period, for a status line.
using ReceiverCallbacks = lidar::ReceiverCallbacks;

// lidar::LiveReceiver<Route>: publish_to(config, model) (model nullopt: from the first data
// packet), run(stop_fd, callbacks), set_clock_sources, data_port(), position_port() (0 when not
// listened to), local_address(), receive_buffer(), counters(), stream(), last_packet_ns()
// (CLOCK_MONOTONIC of the last data packet) and reported_clock(): what the position packets last
// said of the sensor's clock (LidarStream::reported_clock), valid before the stream exists and
// from any thread; the stream's clock check is given it unless set_clock_sources gives another.
class LiveReceiver final : public lidar::LiveReceiver<Route> {
 public:
  // Opens and binds the sockets (joining the multicast group); creates no stream. Errors:
  // invalid_argument for an address that is not one, system_error for a port in use.
  static Expected<LiveReceiver> open(const NetworkConfig& network);

 private:
  explicit LiveReceiver(lidar::LiveReceiver<Route>&& opened) noexcept : lidar::LiveReceiver<Route>(std::move(opened)) {}
};

}  // namespace sim::velodyne
