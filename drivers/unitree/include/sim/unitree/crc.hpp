// SPDX-License-Identifier: Apache-2.0
// The two checksums Unitree LiDARs put on the wire: CRC-32 (L2 packets) and MAVLink's
// CRC-16/MCRF4XX (L1 frames). Table-free for CRC-16 (one frame is ~250 B), table-driven for CRC-32.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace sim::unitree {

// Standard reflected CRC-32 (polynomial 0xEDB88320, init and final xor 0xFFFFFFFF): zlib's crc32.
std::uint32_t crc32(std::span<const std::uint8_t> bytes) noexcept;

// CRC-16/MCRF4XX (the X.25 polynomial, init 0xFFFF, no final xor) as MAVLink accumulates it.
class Crc16Mcrf4xx {
 public:
  void add(std::uint8_t byte) noexcept {
    std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ static_cast<std::uint8_t>(crc_ & 0xFF));
    tmp = static_cast<std::uint8_t>(tmp ^ static_cast<std::uint8_t>(tmp << 4));
    crc_ = static_cast<std::uint16_t>((crc_ >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
  }
  void add(std::span<const std::uint8_t> bytes) noexcept {
    for (const std::uint8_t b : bytes) add(b);
  }
  std::uint16_t value() const noexcept { return crc_; }

 private:
  std::uint16_t crc_ = 0xFFFF;
};

}  // namespace sim::unitree
