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

// NMEA checksum: XOR of the characters between '$' and '*'.
inline std::string nmea(const std::string& body) {
  unsigned sum = 0;
  for (char c : body) sum ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", sum);
  return "$" + body + tail;
}

// A VLP-16-style position packet (554 bytes): timestamp at 198, PPS state at 202, NMEA at 206.
inline std::vector<std::uint8_t> position_packet(std::uint32_t timestamp_us, std::uint8_t pps,
                                                 const std::string& sentence, std::size_t size = 554) {
  std::vector<std::uint8_t> out(size, 0);
  for (int i = 0; i < 4; ++i) out[198 + i] = static_cast<std::uint8_t>(timestamp_us >> (8 * i));
  out[202] = pps;
  std::memcpy(out.data() + 206, sentence.data(), std::min(sentence.size(), size - 206));
  return out;
}

}  // namespace velodyne_test
