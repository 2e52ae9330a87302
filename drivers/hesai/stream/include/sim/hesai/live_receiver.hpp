// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: a Hesai sensor's UDP packets into a LidarStream, the live end of the driver.
//
//   auto receiver = sim::hesai::LiveReceiver::open({.data_port = 2368});   // the socket, nothing else
//   if (!receiver) -> receiver.error().message (one sentence; invalid_argument: a bad address)
//   receiver->publish_to(stream_config, model);       // model nullopt: from the first packet
//   receiver->run(stop_fd, {.tick = print_status});   // until stop_fd is readable
//
// The socket takes datagrams in recvmmsg batches with the kernel's arrival stamps
// (SO_TIMESTAMPNS). Far from a revolution's cut no packet can complete a frame, so the receiver
// naps there and takes the queued packets at once (about 12 per wake-up at 6,000 packets/s);
// near the cut it wakes for each packet, so a finished revolution is published as soon as its
// last packet lands. A gap between arrival stamps longer than the silence timeout means the
// sensor stopped: the revolution in progress is dropped and the next packet starts anew.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/model.hpp"
#include "sim/hesai/route.hpp"
#include "sim/lidar/live_receiver.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

struct NetworkConfig {
  // Where to listen and whom to hear: bind, multicast group, source, receive buffer, silence
  // timeout. IPv4 or IPv6 (lidar::address_problem(…, IpVersions::v4_and_v6) checks an address).
  lidar::UdpListen listen{.receive_buffer = 16 << 20, .versions = lidar::IpVersions::v4_and_v6};
  std::uint16_t data_port = 2368;  // 0: a free port, read back with LiveReceiver::data_port()
};

// datagrams, other_source, unrecognised (not a Hesai point-cloud packet, before the model was
// known) and resumes (packets came back after a silence).
using ReceiveCounters = lidar::ReceiveCounters;
// note: the model detected, packets resumed after a silence; tick: a status line.
using ReceiverCallbacks = lidar::ReceiverCallbacks;

// lidar::LiveReceiver<Route>: publish_to(config, model) (model nullopt: from the first packet),
// run(stop_fd, callbacks), set_clock_sources, data_port(), local_address(), receive_buffer(),
// counters(), stream() (nullptr while the model is not known), last_packet_ns().
class LiveReceiver final : public lidar::LiveReceiver<Route> {
 public:
  // Opens, configures and binds the UDP socket (joining the multicast group when given). Creates
  // no stream: a busy port leaves nothing behind. Errors: invalid_argument for an address that
  // is not one, system_error for a port in use or a socket the system refuses.
  static Expected<LiveReceiver> open(const NetworkConfig& network);

 private:
  explicit LiveReceiver(lidar::LiveReceiver<Route>&& opened) noexcept : lidar::LiveReceiver<Route>(std::move(opened)) {}
};

}  // namespace sim::hesai
