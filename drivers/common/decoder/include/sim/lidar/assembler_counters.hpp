// SPDX-License-Identifier: Apache-2.0
// AssemblerCounters: what every LiDAR family's frame assembler counts (Hesai, Velodyne, Ouster).
// A family derives its own from it and adds what only it can see (Hesai: CRC errors, out of
// order; Ouster: late packets, duplicate columns); the names are the ones the streams print
// (`--summary` keys), so they stay.
//
// Header-only and on the core alone: the family decoders include it.
#pragma once

#include <cstdint>

namespace sim::lidar {

struct AssemblerCounters {
  std::uint64_t packets = 0;                 // decoded
  std::uint64_t malformed = 0;               // rejected: cut short, bad field values
  std::uint64_t lost_packets = 0;            // estimated from the family's gaps
  std::uint64_t frames = 0;                  // completed and returned
  std::uint64_t partial_frames_dropped = 0;  // before the first cut (emit_partial_frames off)
  std::uint64_t dropped_points = 0;          // found no room, no output set, or came too late
};

}  // namespace sim::lidar
