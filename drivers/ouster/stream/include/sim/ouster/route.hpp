// SPDX-License-Identifier: Apache-2.0
// Route: how Ouster datagrams reach a LidarStream, live (LiveReceiver) and in a capture replay:
// the metadata's lidar port (7502) to push, its IMU port (7503) to push_imu, other ports
// nowhere, as ouster-sdk's pcap source routes them. Without ports (by_port false: a replay
// whose user chose the datagrams with --port or --filter) or with one port for both, the size
// tells: the 48-byte datagrams are the IMU's, the rest lidar packets. The stream is made from
// the metadata before the first packet (no model detection).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/lidar/packet_route.hpp"
#include "sim/ouster/lidar_stream.hpp"

namespace sim::ouster {

struct Route {
  using Stream = LidarStream;
  // Larger than the largest Ouster datagram (128 beams, dual profile: 33 kB), so an oversized
  // one arrives whole and is refused by its size rather than cut to a plausible one.
  static constexpr std::size_t datagram_size = 65536;
  static constexpr std::size_t batch_size = 16;   // 1 MiB of buffers
  static constexpr bool refuse_truncated = true;  // counted oversized, never pushed

  std::uint16_t data_port = 7502;  // 0: a free port (live)
  std::uint16_t imu_port = 7503;   // 0: a free port (live)
  bool by_port = true;             // false: the size tells

  std::vector<lidar::RoutedPort> ports() const {
    return {{lidar::PacketKind::data, {data_port, "the lidar", "--lidar-port"}},
            {lidar::PacketKind::imu, {imu_port, "the IMU", "--imu-port"}}};
  }
  lidar::PacketKind operator()(std::uint16_t port, std::span<const std::uint8_t> payload) const noexcept {
    if (by_port && port != data_port && port != imu_port) return lidar::PacketKind::none;
    if (by_port && data_port != imu_port) return port == imu_port ? lidar::PacketKind::imu : lidar::PacketKind::data;
    return payload.size() == imu_packet_bytes ? lidar::PacketKind::imu : lidar::PacketKind::data;
  }
  // An IMU packet; true when it was one (a malformed one is counted).
  static bool push_other(LidarStream& stream, lidar::PacketKind kind, std::span<const std::uint8_t> payload,
                         std::int64_t /*arrival_ns*/) noexcept {
    return kind == lidar::PacketKind::imu && stream.push_imu(payload);
  }
};

}  // namespace sim::ouster
