// SPDX-License-Identifier: Apache-2.0
// Test-only: an independent Ouster packet encoder, written from the firmware user manual's
// "Lidar Data Format" tables (not from the decoder), for the profiles no public capture holds.
// Each field is written at its documented byte offset, little-endian.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ouster_test {

enum class Layout { legacy, rng19, rng19_dual, rng15, fusa_dual };

struct EncodedPixel {
  std::uint32_t range_mm = 0, range2_mm = 0;  // RNG15: multiples of 8
  std::uint8_t reflectivity = 0, reflectivity2 = 0;
  std::uint16_t signal = 0, signal2 = 0, near_ir = 0;  // RNG15 near-IR: multiples of 16, < 4096
};

inline unsigned pixel_size(Layout l) {
  switch (l) {
    case Layout::legacy: case Layout::rng19: return 12;
    case Layout::rng19_dual: return 16;
    case Layout::rng15: return 4;
    case Layout::fusa_dual: return 8;
  }
  return 0;
}

inline const char* profile_name(Layout l) {
  switch (l) {
    case Layout::legacy: return "LEGACY";
    case Layout::rng19: return "RNG19_RFL8_SIG16_NIR16";
    case Layout::rng19_dual: return "RNG19_RFL8_SIG16_NIR16_DUAL";
    case Layout::rng15: return "RNG15_RFL8_NIR8";
    case Layout::fusa_dual: return "FUSA_RNG15_RFL8_NIR8_DUAL";
  }
  return "";
}

inline void put(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v, unsigned bytes) {
  for (unsigned i = 0; i < bytes; ++i) b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

struct PacketSpec {
  Layout layout = Layout::rng19;
  unsigned beams = 32;
  unsigned columns_per_packet = 16;
  std::uint32_t frame_id = 1;
  std::uint32_t init_id = 0x123456;
  std::uint64_t serial = 992100000001;
  std::uint16_t first_column = 0;
  std::uint64_t first_timestamp_ns = 1'000'000'000;
  std::uint64_t column_period_ns = 97'656;  // 1024 × 10 Hz
  bool valid = true;
};

// pixel(column_index_in_frame, beam) gives the values to encode.
template <typename PixelOf>
std::vector<std::uint8_t> encode_packet(const PacketSpec& s, PixelOf pixel) {
  const bool legacy = s.layout == Layout::legacy;
  const std::size_t header = legacy ? 0 : 32;
  const std::size_t column = (legacy ? 16 + 4 : 12) + std::size_t{s.beams} * pixel_size(s.layout);
  std::vector<std::uint8_t> b(header + s.columns_per_packet * column + (legacy ? 0 : 32), 0);
  if (s.layout == Layout::fusa_dual) {
    put(b, 0, 1, 1);                // packet_type u8
    put(b, 1, s.init_id, 3);        // init_id u24
    put(b, 4, s.frame_id, 4);       // frame_id u32
    put(b, 11, s.serial, 5);        // prod_sn u40
  } else if (!legacy) {
    put(b, 0, 1, 2);                // packet_type u16
    put(b, 2, s.frame_id, 2);       // frame_id u16
    put(b, 4, s.init_id, 3);        // init_id u24
    put(b, 7, s.serial, 5);         // prod_sn u40
  }
  for (unsigned c = 0; c < s.columns_per_packet; ++c) {
    const std::size_t at = header + c * column;
    const unsigned m = s.first_column + c;
    put(b, at, s.first_timestamp_ns + m * s.column_period_ns, 8);
    put(b, at + 8, m, 2);
    if (legacy) {
      put(b, at + 10, s.frame_id, 2);
      put(b, at + 12, m * 88, 4);  // encoder count
      put(b, at + column - 4, s.valid ? 0xffffffffu : 0u, 4);
    } else {
      put(b, at + 10, s.valid ? 1 : 0, 2);
    }
    const std::size_t pixels = at + (legacy ? 16 : 12);
    for (unsigned u = 0; u < s.beams; ++u) {
      const EncodedPixel p = pixel(m, u);
      const std::size_t q = pixels + std::size_t{u} * pixel_size(s.layout);
      switch (s.layout) {
        case Layout::legacy:
        case Layout::rng19:
          put(b, q, p.range_mm, 4);
          put(b, q + 4, p.reflectivity, 1);
          put(b, q + 6, p.signal, 2);
          put(b, q + 8, p.near_ir, 2);
          break;
        case Layout::rng19_dual:
          put(b, q, p.range_mm, 3);
          put(b, q + 3, p.reflectivity, 1);
          put(b, q + 4, p.range2_mm, 3);
          put(b, q + 7, p.reflectivity2, 1);
          put(b, q + 8, p.signal, 2);
          put(b, q + 10, p.signal2, 2);
          put(b, q + 12, p.near_ir, 2);
          break;
        case Layout::rng15:
          put(b, q, p.range_mm / 8, 2);
          put(b, q + 2, p.reflectivity, 1);
          put(b, q + 3, p.near_ir / 16, 1);
          break;
        case Layout::fusa_dual:
          put(b, q, p.range_mm / 8, 2);
          put(b, q + 2, p.reflectivity, 1);
          put(b, q + 3, p.near_ir / 16, 1);
          put(b, q + 4, p.range2_mm / 8, 2);
          put(b, q + 6, p.reflectivity2, 1);
          break;
      }
    }
  }
  return b;
}

// A FW 3.x (nested) metadata JSON with simple geometry: beams spread from +20° to −20°, no
// azimuth offsets, no beam origin offset, identity lidar-to-sensor, no pixel shift.
inline std::string nested_metadata(Layout layout, unsigned beams, unsigned columns,
                                   unsigned per_packet, std::uint32_t init_id) {
  std::string altitudes, zeros;
  for (unsigned u = 0; u < beams; ++u) {
    const double alt = 20.0 - 40.0 * u / (beams - 1);
    if (u != 0) altitudes += ',';
    altitudes += std::to_string(alt);
    zeros += u != 0 ? ",0" : "0";
  }
  const std::string identity = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
  return std::string("{\"beam_intrinsics\":{\"beam_altitude_angles\":[") + altitudes +
         "],\"beam_azimuth_angles\":[" + zeros + "],\"beam_to_lidar_transform\":" + identity +
         ",\"lidar_origin_to_beam_origin_mm\":0},\"lidar_intrinsics\":{\"lidar_to_sensor_transform\":" +
         identity + "},\"imu_intrinsics\":{\"imu_to_sensor_transform\":" + identity +
         "},\"lidar_data_format\":{\"columns_per_frame\":" + std::to_string(columns) +
         ",\"columns_per_packet\":" + std::to_string(per_packet) + ",\"pixels_per_column\":" +
         std::to_string(beams) + ",\"pixel_shift_by_row\":[" + zeros +
         "],\"column_window\":[0," + std::to_string(columns - 1) + "],\"udp_profile_lidar\":\"" +
         profile_name(layout) + "\",\"udp_profile_imu\":\"LEGACY\"},\"config_params\":{\"lidar_mode\":\"" +
         std::to_string(columns) + "x10\",\"udp_port_lidar\":7502,\"udp_port_imu\":7503},"
         "\"sensor_info\":{\"prod_line\":\"OS-2-" + std::to_string(beams) + "\",\"prod_sn\":\"992100000001\","
         "\"build_rev\":\"v3.0.1\",\"initialization_id\":" + std::to_string(init_id) + "}}";
}

}  // namespace ouster_test
