// SPDX-License-Identifier: Apache-2.0
// One IMU sample, as published on a LiDAR's IMU stream (one SIM frame per sample, raw layout).
// Plain data with fixed size so readers in other processes can view a frame as this struct.
#pragma once

#include <cstdint>
#include <type_traits>

namespace sim::unitree {

struct ImuSample {
  std::int64_t stamp_ns = 0;             // sensor clock (L2) or host receive time (L1)
  // x, y, z, w. The L2 sends (w, x, y, z) and is reordered; the L1's wire order is undetermined
  // and taken as the vendor labels it (docs/unitree.md).
  float quaternion[4] = {0, 0, 0, 1};
  float angular_velocity[3] = {0, 0, 0};     // rad/s
  float linear_acceleration[3] = {0, 0, 0};  // m/s²
  std::uint32_t seq = 0;                 // L2 packet seq, or L1 packet_id
  std::uint32_t reserved = 0;
};

static_assert(std::is_trivially_copyable_v<ImuSample>);
static_assert(sizeof(ImuSample) == 56, "ImuSample is part of the IMU stream's frame layout");

}  // namespace sim::unitree
