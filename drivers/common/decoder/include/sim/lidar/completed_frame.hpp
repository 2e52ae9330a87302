// SPDX-License-Identifier: Apache-2.0
// CompletedFrame: what every LiDAR family's frame assembler says of a frame it completed
// (Hesai, Velodyne, Ouster). A family that knows more derives from it (Hesai: the motor speed
// and functional safety; Ouster: the frame id and column counts), so the stream's
// PointPipeline publishes every family's frame the same way, without asking which one it is.
//
// Header-only and on the core alone: the family decoders include it (docs/architecture.md,
// "LiDAR decoder common").
#pragma once

#include <cstddef>
#include <cstdint>

namespace sim::lidar {

struct CompletedFrame {
  std::size_t point_count = 0;       // points written at the front of the output span
  std::int64_t stamp_ns = 0;         // sensor time of the frame (the family says which point's)
  std::int64_t host_receive_ns = 0;  // host receive time of the frame's first packet
  std::uint64_t index = 0;           // 0, 1, 2… frames completed by this assembler
  std::uint32_t packets = 0;         // packets that contributed to the frame
  // Packets missing inside the frame, as the family estimates them (sequence numbers, azimuth
  // or time gaps; Ouster: its missing columns rounded up to whole packets).
  std::uint32_t lost_packets = 0;
  std::uint32_t dropped_points = 0;  // points that found no room (output span or carry-over full)
  // A whole revolution (Hesai, Velodyne: began at a cut and ended at the next) or a whole
  // column window (Ouster: began at the window's first column); false for a partial frame.
  bool whole = true;
};

}  // namespace sim::lidar
