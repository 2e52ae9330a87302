// SPDX-License-Identifier: Apache-2.0
// Route: how Velodyne datagrams reach a LidarStream, live (LiveReceiver) and in a capture
// replay: data packets (1206 bytes, port 2368) to push, position packets (port 8308: GPRMC,
// PPS) to push_position. Live a datagram takes its socket's push; a replay routes by the
// datagram's destination port, and one to neither port (a capture filtered with --port or
// --filter, or recorded on other ports) by its size. The model is given or named by the first
// data packet.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/lidar/packet_route.hpp"
#include "sim/velodyne/lidar_stream.hpp"

namespace sim::velodyne {

struct Route {
  using Stream = LidarStream;
  using Config = LidarStreamConfig;
  using Model = velodyne::Model;
  // Data packets are 1206 bytes, position packets 512 or 554: a larger buffer lets an oversized
  // datagram arrive whole and be refused by its size instead of cut to a plausible one.
  static constexpr std::size_t datagram_size = 2048;
  static constexpr std::size_t batch_size = 32;
  static constexpr bool refuse_truncated = false;  // pushed, and refused by the packet's size

  std::uint16_t data_port = default_data_port;                         // 0: a free port (live)
  std::optional<std::uint16_t> position_port = default_position_port;  // nullopt: not listened to

  std::vector<lidar::RoutedPort> ports() const {
    std::vector<lidar::RoutedPort> ports{{lidar::PacketKind::data, {data_port, "UDP", "--port"}}};
    if (position_port) {
      ports.push_back({lidar::PacketKind::position, {*position_port, "the position", "--position-port"}});
    }
    return ports;
  }
  lidar::PacketKind operator()(std::uint16_t port, std::span<const std::uint8_t> payload) const noexcept {
    if (port != 0 && port == data_port) return lidar::PacketKind::data;
    if (port != 0 && port == position_port) return lidar::PacketKind::position;
    return payload.size() == packet_size ? lidar::PacketKind::data : lidar::PacketKind::position;
  }
  // A position packet (a stray datagram is counted malformed); true when it was one.
  static bool push_other(LidarStream& stream, lidar::PacketKind kind, std::span<const std::uint8_t> payload,
                         std::int64_t arrival_ns) noexcept {
    return kind == lidar::PacketKind::position && stream.push_position(payload, arrival_ns);
  }
  static std::optional<Model> detect_model(std::span<const std::uint8_t> payload) noexcept {
    return velodyne::detect_model(payload);
  }
  static std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
    return velodyne::returns_in(payload, model);
  }
  // Live stamps are the sensor's clock; nothing is known of it before a position packet.
  static ClockStatus reported_before_stream() {
    ClockStatus clock;
    clock.stamps = sim::StampClock::sensor;
    return clock;
  }
};

}  // namespace sim::velodyne
