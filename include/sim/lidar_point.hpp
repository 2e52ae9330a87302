// SPDX-License-Identifier: Apache-2.0
// The one point layout every LiDAR stream in SIM uses (Layout::points with PointType::lidar_point).
//
// Coordinates are in the sensor's own frame, in metres, as the manufacturer defines it:
// for Hesai, x = d·cos(el)·sin(az), y = d·cos(el)·cos(az), z = d·sin(el) (y forward at azimuth 0,
// x to the right, z up); for Unitree, the formulas of its SDK. Drivers do no extrinsic transform.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace sim {

struct LidarPoint {
  float x;                      // metres
  float y;                      // metres
  float z;                      // metres
  float intensity;              // sensor reflectivity, 0–255 for Hesai and Unitree
  std::uint32_t time_offset_ns;  // time of this firing after the frame's stamp_ns
  std::uint16_t ring;           // laser channel, 0-based, in the calibration file's order
  std::uint8_t return_index;    // 0 for the first return of a firing block group, 1 for the next…
  std::uint8_t reserved;        // zero
};

static_assert(std::is_trivially_copyable_v<LidarPoint>);
static_assert(std::is_standard_layout_v<LidarPoint>);
static_assert(sizeof(LidarPoint) == 24, "LidarPoint is part of the shared-memory ABI");
static_assert(offsetof(LidarPoint, intensity) == 12);
static_assert(offsetof(LidarPoint, time_offset_ns) == 16);
static_assert(offsetof(LidarPoint, ring) == 20);

}  // namespace sim
