// SPDX-License-Identifier: Apache-2.0
// Route: how Hesai datagrams reach a LidarStream, live (LiveReceiver) and in a capture replay.
// A Hesai sensor sends point-cloud packets alone, on one port (2368): every datagram is a data
// packet (push); one that is not is counted by the stream. The model is given or named by the
// first packet (detect_model; returns_in raises the stream's capacity).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/model.hpp"
#include "sim/lidar/packet_route.hpp"

namespace sim::hesai {

struct Route {
  using Stream = LidarStream;
  using Config = LidarStreamConfig;
  using Model = hesai::Model;
  // The largest Hesai payload is 1392 bytes; a larger buffer lets an oversized datagram arrive
  // whole and be rejected by its size instead of silently cut to a plausible one.
  static constexpr std::size_t datagram_size = 9000;
  static constexpr std::size_t batch_size = 32;
  static constexpr bool refuse_truncated = false;  // pushed, and refused by the packet's size

  std::uint16_t data_port = 2368;  // 0: a free port (live)

  std::vector<lidar::RoutedPort> ports() const { return {{lidar::PacketKind::data, {data_port, "UDP", "--port"}}}; }
  lidar::PacketKind operator()(std::uint16_t /*port*/, std::span<const std::uint8_t> /*payload*/) const noexcept {
    return lidar::PacketKind::data;
  }
  static std::optional<Model> detect_model(std::span<const std::uint8_t> payload) noexcept {
    return hesai::detect_model(payload);
  }
  static std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept {
    return hesai::returns_in(payload, model);
  }
};

}  // namespace sim::hesai
