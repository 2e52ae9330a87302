// SPDX-License-Identifier: Apache-2.0
// Test-only, independent of the decoder: builds Velodyne data and position packets byte by byte
// from the documented format (reference lidar-velodyne-ouster.md §1, the user manuals), so
// the tests can feed models no capture exists for (HDL-32E, HDL-64E, VLP-32C dual).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace velodyne_test {

struct Unit {
  std::uint16_t distance = 0;  // raw units (2 or 4 mm)
  std::uint8_t reflectivity = 0;
};

struct Block {
  std::uint8_t flag = 0xEE;  // second byte of the flag: EE, DD, CC, BB
  std::uint16_t azimuth = 0;  // 0.01°
  std::array<Unit, 32> units{};
};

struct DataPacket {
  std::array<Block, 12> blocks{};
  std::uint32_t timestamp_us = 0;
  std::uint8_t return_mode = 0x37;
  std::uint8_t product_id = 0x22;

  std::vector<std::uint8_t> bytes() const {
    std::vector<std::uint8_t> out(1206, 0);
    for (std::size_t b = 0; b < 12; ++b) {
      std::uint8_t* p = out.data() + b * 100;
      p[0] = 0xFF;
      p[1] = blocks[b].flag;
      p[2] = static_cast<std::uint8_t>(blocks[b].azimuth & 0xFF);
      p[3] = static_cast<std::uint8_t>(blocks[b].azimuth >> 8);
      for (std::size_t u = 0; u < 32; ++u) {
        p[4 + u * 3] = static_cast<std::uint8_t>(blocks[b].units[u].distance & 0xFF);
        p[5 + u * 3] = static_cast<std::uint8_t>(blocks[b].units[u].distance >> 8);
        p[6 + u * 3] = blocks[b].units[u].reflectivity;
      }
    }
    for (int i = 0; i < 4; ++i) out[1200 + i] = static_cast<std::uint8_t>(timestamp_us >> (8 * i));
    out[1204] = return_mode;
    out[1205] = product_id;
    return out;
  }
};

// HDL-64E S3 in dual return (the S3 user manual's dual-return packet, as valgur/velodyne_decoder
// reads it): three firings per packet, each as four blocks with the firing's azimuth: upper
// strongest (FF EE, lasers 0–31), lower strongest (FF DD, lasers 32–63), upper last, lower last.
// `unit(f, laser, last)` gives firing f's (0–2) return. Bytes 1204–1205 are the rotating status.
template <typename UnitOf>
DataPacket hdl64e_dual_packet(std::uint32_t timestamp_us, const std::array<std::uint16_t, 3>& azimuths,
                              UnitOf unit) {
  DataPacket p;
  p.timestamp_us = timestamp_us;
  p.return_mode = 'T';  // a status type (temperature), not a return mode
  p.product_id = 41;
  for (unsigned f = 0; f < 3; ++f) {
    for (unsigned b = 0; b < 4; ++b) {
      const bool lower = b % 2 == 1;
      const bool last = b >= 2;
      Block& block = p.blocks[f * 4 + b];
      block.flag = lower ? 0xDD : 0xEE;
      block.azimuth = azimuths[f];
      for (unsigned u = 0; u < 32; ++u) block.units[u] = unit(f, (lower ? 32U : 0U) + u, last);
    }
  }
  return p;
}

// NMEA checksum: XOR of the characters between '$' and '*'.
inline std::string nmea(const std::string& body) {
  unsigned sum = 0;
  for (char c : body) sum ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", sum);
  return "$" + body + tail;
}

// A position packet as a VLP-16 sends it (512 bytes of UDP payload, 554 on the wire): timestamp
// at 198, PPS state at 202, NMEA at 206.
inline std::vector<std::uint8_t> position_packet(std::uint32_t timestamp_us, std::uint8_t pps,
                                                 const std::string& sentence, std::size_t size = 512) {
  std::vector<std::uint8_t> out(size, 0);
  for (int i = 0; i < 4; ++i) out[198 + i] = static_cast<std::uint8_t>(timestamp_us >> (8 * i));
  out[202] = pps;
  std::memcpy(out.data() + 206, sentence.data(), std::min(sentence.size(), size - 206));
  return out;
}

}  // namespace velodyne_test
