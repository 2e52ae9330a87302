// SPDX-License-Identifier: Apache-2.0
// Little-endian field access into wire bytes, at an offset: every family's readers
// (sim/lidar/little_endian.hpp). The callers check bounds once per packet (packet sizes are
// fixed per type), so these take an offset the caller has already validated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "sim/lidar/little_endian.hpp"

namespace sim::unitree::le {

inline std::uint16_t u16(std::span<const std::uint8_t> b, std::size_t off) noexcept { return lidar::le16(b.data() + off); }
inline std::uint32_t u32(std::span<const std::uint8_t> b, std::size_t off) noexcept { return lidar::le32(b.data() + off); }
inline float f32(std::span<const std::uint8_t> b, std::size_t off) noexcept { return lidar::le_f32(b.data() + off); }

}  // namespace sim::unitree::le
