// SPDX-License-Identifier: Apache-2.0
// Little-endian field access into wire bytes. The callers check bounds once per packet (packet
// sizes are fixed per type), so these helpers take an offset the caller has already validated.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

namespace sim::unitree::le {

inline std::uint16_t u16(std::span<const std::uint8_t> b, std::size_t off) noexcept {
  return static_cast<std::uint16_t>(static_cast<unsigned>(b[off]) |
                                    (static_cast<unsigned>(b[off + 1]) << 8));
}
inline std::uint32_t u32(std::span<const std::uint8_t> b, std::size_t off) noexcept {
  return static_cast<std::uint32_t>(b[off]) | (static_cast<std::uint32_t>(b[off + 1]) << 8) |
         (static_cast<std::uint32_t>(b[off + 2]) << 16) |
         (static_cast<std::uint32_t>(b[off + 3]) << 24);
}
inline float f32(std::span<const std::uint8_t> b, std::size_t off) noexcept {
  return std::bit_cast<float>(u32(b, off));
}

}  // namespace sim::unitree::le
