// SPDX-License-Identifier: Apache-2.0
// Test-only: builds Hesai packets byte by byte from the layouts in the reference notes
// (lidar-wire-formats.md §4 XT16/XT32, §5 QT64), for the models no public capture exists of.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace hesai_test {

struct SyntheticPacket {
  unsigned channels = 16;             // XT: 16 or 32
  std::uint8_t return_mode = 0x38;    // last
  unsigned returns = 1;
  std::uint16_t first_azimuth = 0;    // 0.01°
  std::uint16_t azimuth_step = 18;    // 0.01° between firing groups
  std::uint16_t rpm = 600;
  std::array<std::uint8_t, 6> utc{119, 3, 4, 5, 6, 7};  // 2019-03-04 05:06:07
  std::uint32_t micros = 250000;
  std::uint32_t sequence = 1;
  // Raw distance (×4 mm) and reflectivity of (block, channel); default: channel+1 metres.
  std::function<std::uint16_t(unsigned block, unsigned channel)> distance =
      [](unsigned, unsigned ch) { return static_cast<std::uint16_t>((ch + 1) * 250); };
  std::function<std::uint8_t(unsigned block, unsigned channel)> reflectivity =
      [](unsigned, unsigned ch) { return static_cast<std::uint8_t>(ch); };
};

inline void put16(std::vector<std::uint8_t>& p, std::size_t at, std::uint16_t v) {
  p[at] = static_cast<std::uint8_t>(v);
  p[at + 1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put32(std::vector<std::uint8_t>& p, std::size_t at, std::uint32_t v) {
  for (unsigned i = 0; i < 4; ++i) p[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Protocol 6.1: 12-byte header, 8 blocks of 2 + 4·N bytes, 24-byte tail, 4-byte sequence.
inline std::vector<std::uint8_t> build_xt(const SyntheticPacket& s) {
  const std::size_t block_size = 2 + 4 * std::size_t{s.channels};
  std::vector<std::uint8_t> p(12 + 8 * block_size + 28, 0);
  p[0] = 0xEE;
  p[1] = 0xFF;
  p[2] = 6;
  p[3] = 1;
  p[6] = static_cast<std::uint8_t>(s.channels);
  p[7] = 8;
  p[8] = 1;
  p[9] = 4;
  p[10] = static_cast<std::uint8_t>(s.returns);
  p[11] = 1;
  for (unsigned b = 0; b < 8; ++b) {
    const std::size_t at = 12 + b * block_size;
    put16(p, at, static_cast<std::uint16_t>((s.first_azimuth + (b / s.returns) * s.azimuth_step) % 36000));
    for (unsigned c = 0; c < s.channels; ++c) {
      put16(p, at + 2 + 4 * c, s.distance(b, c));
      p[at + 2 + 4 * c + 2] = s.reflectivity(b, c);
    }
  }
  const std::size_t tail = 12 + 8 * block_size;
  p[tail + 10] = s.return_mode;
  put16(p, tail + 11, s.rpm);
  for (unsigned i = 0; i < 6; ++i) p[tail + 13 + i] = s.utc[i];
  put32(p, tail + 19, s.micros);
  p[tail + 23] = 0x42;
  put32(p, tail + 24, s.sequence);
  return p;
}

// Protocol 3.1 (QT64): 12-byte header, 4 blocks of 2 + 4·64 bytes, 24-byte tail, sequence.
inline std::vector<std::uint8_t> build_qt64(const SyntheticPacket& s) {
  constexpr std::size_t block_size = 2 + 4 * 64;
  std::vector<std::uint8_t> p(12 + 4 * block_size + 28, 0);
  p[0] = 0xEE;
  p[1] = 0xFF;
  p[2] = 3;
  p[3] = 1;
  p[6] = 64;
  p[7] = 4;
  p[8] = 1;
  p[9] = 4;
  p[10] = static_cast<std::uint8_t>(s.returns);
  p[11] = 1;
  for (unsigned b = 0; b < 4; ++b) {
    const std::size_t at = 12 + b * block_size;
    put16(p, at, static_cast<std::uint16_t>((s.first_azimuth + (b / s.returns) * s.azimuth_step) % 36000));
    for (unsigned c = 0; c < 64; ++c) {
      put16(p, at + 2 + 4 * c, s.distance(b, c));
      p[at + 2 + 4 * c + 2] = s.reflectivity(b, c);
    }
  }
  const std::size_t tail = 12 + 4 * block_size;  // 1044
  put16(p, tail + 10, s.rpm);
  put32(p, tail + 12, s.micros);
  p[tail + 16] = s.return_mode;
  p[tail + 17] = 0x42;
  for (unsigned i = 0; i < 6; ++i) p[tail + 18 + i] = s.utc[i];
  put32(p, tail + 24, s.sequence);
  return p;
}

}  // namespace hesai_test
