// SPDX-License-Identifier: Apache-2.0
// The words of a family's route (hesai::Route, velodyne::Route, ouster::Route): which push of
// the family's stream a datagram takes, and on which socket it arrives live. A route is one
// small value type beside the family's stream, used by the live receiver (LiveReceiver<Route>,
// live_receiver.hpp) and by the capture replay, so both route a datagram the same way.
#pragma once

#include <cstdint>

#include "sim/lidar/udp_receiver.hpp"

namespace sim::lidar {

// Which push of its family's stream a datagram takes: data (push), position (push_position),
// imu (push_imu); none: not the stream's (a datagram to another port).
enum class PacketKind : std::uint8_t { data, position, imu, none };

// One socket of a route: the packets that arrive on it, its port and how messages name it.
struct RoutedPort {
  PacketKind kind = PacketKind::data;
  UdpPort udp;
};

}  // namespace sim::lidar
