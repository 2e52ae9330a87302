// SPDX-License-Identifier: Apache-2.0
// The little-endian fields of LiDAR packets (every family's wire order), read from bytes at any
// alignment. Written with shifts, which GCC and clang compile to one load on a little-endian
// host and which are right on a big-endian one; inline, so a packet accessor costs what it did
// when each family had its own copy. The caller has checked that the bytes are there.
//
// Header-only and on the core alone: the family decoders include it.
#pragma once

#include <cstdint>
#include <cstring>

namespace sim::lidar {

inline std::uint16_t le16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t le32(const std::uint8_t* p) noexcept {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}
inline std::uint64_t le64(const std::uint8_t* p) noexcept {
  return std::uint64_t{le32(p)} | (std::uint64_t{le32(p + 4)} << 32);
}
// A field of `bytes` bytes (at most 8) that is no machine word: Ouster's 24-bit init_id and
// 40-bit serial number.
inline std::uint64_t le_uint(const std::uint8_t* p, unsigned bytes) noexcept {
  std::uint64_t value = 0;
  for (unsigned i = 0; i < bytes && i < 8; ++i) value |= std::uint64_t{p[i]} << (8 * i);
  return value;
}
// An IEEE 754 single in little-endian order.
inline float le_f32(const std::uint8_t* p) noexcept {
  const std::uint32_t bits = le32(p);
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

}  // namespace sim::lidar
