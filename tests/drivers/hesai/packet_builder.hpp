// SPDX-License-Identifier: Apache-2.0
// Test-only: builds Hesai packets byte by byte from the layouts in the reference notes
// (lidar-wire-formats.md §4 XT16/XT32, §5 QT64; hesai-qt128-xt32m.md for the XT32M and the
// QT128), for the models no public capture exists of, and QT128 packets with chosen faults.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace hesai_test {

struct SyntheticPacket {
  unsigned channels = 16;             // XT: 16 or 32
  unsigned blocks = 8;                // XT16/XT32: 8, XT32M: 6
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
  // QT128 only: tail mode flag (bit 0: a multi-return packet fired the first loop), the
  // functional-safety bytes 1–4 (state/fault type/counter, fault count/id, fault code), and
  // whether the 32-byte signature area follows.
  std::uint8_t mode_flag = 1;
  std::array<std::uint8_t, 4> safety{0x20, 0, 0, 0};  // state 1 = normal
  bool signature = true;
};

// CRC-32/MPEG-2, bit by bit: the test's own, independent of the decoder's table version.
inline std::uint32_t crc32_mpeg2(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= std::uint32_t{p[i]} << 24;
    for (int k = 0; k < 8; ++k) c = (c & 0x80000000u) ? (c << 1) ^ 0x04C11DB7u : c << 1;
  }
  return c;
}

inline void put16(std::vector<std::uint8_t>& p, std::size_t at, std::uint16_t v) {
  p[at] = static_cast<std::uint8_t>(v);
  p[at + 1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put32(std::vector<std::uint8_t>& p, std::size_t at, std::uint32_t v) {
  for (unsigned i = 0; i < 4; ++i) p[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Protocol 6.1: 12-byte header, 8 (XT32M: 6) blocks of 2 + 4·N bytes, 24-byte tail, 4-byte
// sequence.
inline std::vector<std::uint8_t> build_xt(const SyntheticPacket& s) {
  const std::size_t block_size = 2 + 4 * std::size_t{s.channels};
  std::vector<std::uint8_t> p(12 + s.blocks * block_size + 28, 0);
  p[0] = 0xEE;
  p[1] = 0xFF;
  p[2] = 6;
  p[3] = 1;
  p[6] = static_cast<std::uint8_t>(s.channels);
  p[7] = static_cast<std::uint8_t>(s.blocks);
  p[8] = 1;
  p[9] = 4;
  p[10] = static_cast<std::uint8_t>(s.returns);
  p[11] = 1;
  for (unsigned b = 0; b < s.blocks; ++b) {
    const std::size_t at = 12 + b * block_size;
    put16(p, at, static_cast<std::uint16_t>((s.first_azimuth + (b / s.returns) * s.azimuth_step) % 36000));
    for (unsigned c = 0; c < s.channels; ++c) {
      put16(p, at + 2 + 4 * c, s.distance(b, c));
      p[at + 2 + 4 * c + 2] = s.reflectivity(b, c);
    }
  }
  const std::size_t tail = 12 + s.blocks * block_size;
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

// Protocol 3.2 (QT128C2X): header 12, 2 blocks of 2 + 128·4, body CRC, functional safety 17,
// tail 34, optional 32-byte signature; every CRC correct. The channels dark in a block's
// firing loop (0–31 in the first, 32–63 in the second) get distance 0, as on the sensor.
inline std::vector<std::uint8_t> build_qt128(const SyntheticPacket& s) {
  constexpr std::size_t block_size = 2 + 128 * 4;
  std::vector<std::uint8_t> p(1095 + (s.signature ? 32 : 0), 0);
  p[0] = 0xEE;
  p[1] = 0xFF;
  p[2] = 3;
  p[3] = 2;
  p[6] = 128;
  p[7] = 2;
  p[8] = 1;
  p[9] = 4;
  p[10] = static_cast<std::uint8_t>(s.returns);
  p[11] = 0x1d;
  for (unsigned b = 0; b < 2; ++b) {
    const std::size_t at = 12 + b * block_size;
    put16(p, at, static_cast<std::uint16_t>((s.first_azimuth + (b / s.returns) * s.azimuth_step) % 36000));
    const bool first_loop = s.returns == 1 ? b == 0 : (s.mode_flag & 1) != 0;
    for (unsigned c = 0; c < 128; ++c) {
      const bool dark = first_loop ? c < 32 : (c >= 32 && c < 64);
      put16(p, at + 2 + 4 * c, dark ? 0 : s.distance(b, c));
      p[at + 2 + 4 * c + 2] = s.reflectivity(b, c);
    }
  }
  put32(p, 1040, crc32_mpeg2(p.data() + 12, 1028));
  constexpr std::size_t fs = 1044;
  p[fs] = 1;
  for (unsigned i = 0; i < 4; ++i) p[fs + 1 + i] = s.safety[i];
  put32(p, fs + 13, crc32_mpeg2(p.data() + fs + 1, 12));
  constexpr std::size_t tail = 1061;
  p[tail + 5] = s.mode_flag;
  p[tail + 12] = s.return_mode;
  put16(p, tail + 13, s.rpm);
  for (unsigned i = 0; i < 6; ++i) p[tail + 15 + i] = s.utc[i];
  put32(p, tail + 21, s.micros);
  p[tail + 25] = 0x42;
  put32(p, tail + 26, s.sequence);
  put32(p, tail + 30, crc32_mpeg2(p.data() + tail, 30));
  return p;
}

}  // namespace hesai_test
