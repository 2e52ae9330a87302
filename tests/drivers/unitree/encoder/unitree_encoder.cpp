// SPDX-License-Identifier: Apache-2.0
#include "unitree_encoder.hpp"

#include <bit>
#include <cstring>

namespace unitree_test {
namespace {

void put_u8(Bytes& b, std::size_t off, std::uint8_t v) { b.at(off) = std::uint8_t{v}; }
void put_u16(Bytes& b, std::size_t off, std::uint16_t v) {
  put_u8(b, off, static_cast<std::uint8_t>(v & 0xFF));
  put_u8(b, off + 1, static_cast<std::uint8_t>(v >> 8));
}
void put_u32(Bytes& b, std::size_t off, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) put_u8(b, off + i, static_cast<std::uint8_t>(v >> (8 * i)));
}
void put_f32(Bytes& b, std::size_t off, float v) { put_u32(b, off, std::bit_cast<std::uint32_t>(v)); }

// Bit by bit, straight from the definition (poly 0x1021 reflected = 0x8408, init 0xFFFF).
std::uint16_t x25_accumulate(std::uint16_t crc, std::uint8_t byte) {
  crc ^= byte;
  for (int k = 0; k < 8; ++k) {
    crc = (crc & 1U) ? static_cast<std::uint16_t>((crc >> 1) ^ 0x8408U)
                     : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

}  // namespace

std::uint32_t reference_crc32(std::span<const std::uint8_t> bytes) {
  std::uint32_t crc = 0xFFFFFFFFU;
  for (const std::uint8_t b : bytes) {
    crc ^= static_cast<std::uint32_t>(b);
    for (int k = 0; k < 8; ++k) crc = (crc & 1U) ? (crc >> 1) ^ 0xEDB88320U : crc >> 1;
  }
  return ~crc;
}

Bytes l2_packet(std::uint32_t type, std::span<const std::uint8_t> data) {
  const std::size_t size = 12 + data.size() + 12;
  Bytes b(size);
  put_u8(b, 0, 0x55);
  put_u8(b, 1, 0xAA);
  put_u8(b, 2, 0x05);
  put_u8(b, 3, 0x0A);
  put_u32(b, 4, type);
  put_u32(b, 8, static_cast<std::uint32_t>(size));
  std::memcpy(b.data() + 12, data.data(), data.size());
  const std::size_t tail = 12 + data.size();
  put_u32(b, tail, reference_crc32(data));  // data only (reference §7)
  put_u32(b, tail + 4, type);               // msg_type_check: not checked by receivers
  put_u8(b, tail + 10, 0x00);
  put_u8(b, tail + 11, 0xFF);
  return b;
}

Bytes l2_point_packet(const L2PointSpec& s) {
  // Build the whole packet with absolute offsets (table §7.1), then take its data part.
  Bytes p(1044);
  put_u32(p, 12, s.seq);
  put_u32(p, 16, 1020);
  put_u32(p, 20, s.stamp_sec);
  put_u32(p, 24, s.stamp_nsec);
  put_f32(p, 64, s.a_axis_dist);
  put_f32(p, 68, s.b_axis_dist);
  put_f32(p, 72, s.theta_angle_bias);
  put_f32(p, 76, s.alpha_angle_bias);
  put_f32(p, 80, s.beta_angle);
  put_f32(p, 84, s.xi_angle);
  put_f32(p, 88, s.range_bias);
  put_f32(p, 92, s.range_scale);
  put_f32(p, 96, s.com_horizontal_angle_start);
  put_f32(p, 100, s.com_horizontal_angle_step);
  put_f32(p, 104, s.scan_period);
  put_f32(p, 108, s.range_min);
  put_f32(p, 112, s.range_max);
  put_f32(p, 116, s.angle_min);
  put_f32(p, 120, s.angle_increment);
  put_f32(p, 124, s.time_increment);
  put_u32(p, 128, s.point_num);
  for (std::size_t j = 0; j < 300; ++j) {
    put_u16(p, 132 + 2 * j, s.ranges[j]);
    put_u8(p, 732 + j, s.intensities[j]);
  }
  return l2_packet(102, std::span<const std::uint8_t>(p).subspan(12, 1020));
}

Bytes l2_2d_packet(const L2Point2dSpec& s) {
  Bytes p(5536);
  put_u32(p, 12, s.seq);
  put_u32(p, 16, 5512);
  put_f32(p, 64, s.a_axis_dist);
  put_f32(p, 76, s.alpha_angle_bias);
  put_f32(p, 88, s.range_bias);
  put_f32(p, 92, s.range_scale);
  put_f32(p, 96, 0.1F);
  put_f32(p, 100, s.range_min);
  put_f32(p, 104, s.range_max);
  put_f32(p, 108, s.angle_min);
  put_f32(p, 112, s.angle_increment);
  put_f32(p, 116, s.time_increment);
  put_u32(p, 120, s.point_num);
  for (std::size_t j = 0; j < 1800; ++j) {
    put_u16(p, 124 + 2 * j, s.ranges.at(j));
    put_u8(p, 3724 + j, s.intensities.at(j));
  }
  return l2_packet(103, std::span<const std::uint8_t>(p).subspan(12, 5512));
}

Bytes l2_imu_packet(const L2ImuSpec& s) {
  Bytes p(80);
  put_u32(p, 12, s.seq);
  put_u32(p, 16, 40);
  put_u32(p, 20, s.stamp_sec);
  put_u32(p, 24, s.stamp_nsec);
  for (std::size_t i = 0; i < 4; ++i) put_f32(p, 28 + 4 * i, s.quaternion_wxyz[i]);
  for (std::size_t i = 0; i < 3; ++i) {
    put_f32(p, 44 + 4 * i, s.angular_velocity[i]);
    put_f32(p, 56 + 4 * i, s.linear_acceleration[i]);
  }
  return l2_packet(104, std::span<const std::uint8_t>(p).subspan(12, 56));
}

Bytes robosense_packet() {
  // RoboSense MSOP header 55 AA 05 0A 5A A5 50 A0, then payload: 1248 B in all.
  Bytes b(1248, std::uint8_t{0x11});
  const std::uint8_t head[8] = {0x55, 0xAA, 0x05, 0x0A, 0x5A, 0xA5, 0x50, 0xA0};
  for (std::size_t i = 0; i < 8; ++i) put_u8(b, i, head[i]);
  return b;
}

Bytes mavlink_frame(const MavlinkSpec& s, std::span<const std::uint8_t> full_payload) {
  std::size_t len = full_payload.size();
  if (s.trim) {
    // MAVLink v2 drops trailing zeros but always sends at least one payload byte.
    while (len > 1 && full_payload[len - 1] == std::uint8_t{0}) --len;
  }
  Bytes b(10 + len + 2 + (s.signed_frame ? 13 : 0));
  put_u8(b, 0, 0xFD);
  put_u8(b, 1, static_cast<std::uint8_t>(len));
  put_u8(b, 2, s.signed_frame ? 0x01 : 0x00);
  put_u8(b, 3, 0);
  put_u8(b, 4, s.seq);
  put_u8(b, 5, s.sysid);
  put_u8(b, 6, s.compid);
  put_u8(b, 7, static_cast<std::uint8_t>(s.msgid & 0xFF));
  put_u8(b, 8, static_cast<std::uint8_t>((s.msgid >> 8) & 0xFF));
  put_u8(b, 9, static_cast<std::uint8_t>((s.msgid >> 16) & 0xFF));
  std::memcpy(b.data() + 10, full_payload.data(), len);
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 1; i < 10 + len; ++i) crc = x25_accumulate(crc, static_cast<std::uint8_t>(b[i]));
  crc = x25_accumulate(crc, s.crc_extra);
  put_u16(b, 10 + len, crc);
  for (std::size_t i = 0; s.signed_frame && i < 13; ++i) {
    put_u8(b, 12 + len + i, static_cast<std::uint8_t>(0xA0 + i));
  }
  return b;
}

Bytes l1_distance_payload(std::uint16_t packet_id, const std::array<std::uint16_t, 120>& ranges) {
  Bytes p(246);
  put_u16(p, 0, packet_id);
  put_u16(p, 2, 120);
  put_u16(p, 4, 240);
  for (std::size_t j = 0; j < 120; ++j) put_u16(p, 6 + 2 * j, ranges[j]);
  return p;
}

Bytes l1_auxiliary_payload(const L1AuxSpec& s) {
  Bytes p(209);
  put_u32(p, 12, s.sys_rotation_period);
  put_u32(p, 16, s.com_rotation_period);
  put_f32(p, 20, s.com_horizontal_angle_start);
  put_f32(p, 24, s.com_horizontal_angle_step);
  put_f32(p, 28, s.sys_vertical_angle_start);
  put_f32(p, 32, s.sys_vertical_angle_span);
  put_f32(p, 72, s.b_axis_dist);
  put_f32(p, 76, s.theta_angle);
  put_f32(p, 80, s.ksi_angle);
  put_u16(p, 84, s.packet_id);
  put_u16(p, 86, 120);
  for (std::size_t j = 0; j < 120; ++j) put_u8(p, 89 + j, s.reflect[j]);
  return p;
}

Bytes l1_imu_payload(const std::array<float, 4>& q, const std::array<float, 3>& gyro,
                     const std::array<float, 3>& acc, std::uint16_t packet_id) {
  Bytes p(42);
  for (std::size_t i = 0; i < 4; ++i) put_f32(p, 4 * i, q[i]);
  for (std::size_t i = 0; i < 3; ++i) {
    put_f32(p, 16 + 4 * i, gyro[i]);
    put_f32(p, 28 + 4 * i, acc[i]);
  }
  put_u16(p, 40, packet_id);
  return p;
}

Bytes l1_distance_frame(std::uint16_t packet_id, const std::array<std::uint16_t, 120>& ranges,
                        std::uint8_t seq) {
  return mavlink_frame({16, 74, seq}, l1_distance_payload(packet_id, ranges));
}
Bytes l1_auxiliary_frame(const L1AuxSpec& spec, std::uint8_t seq) {
  return mavlink_frame({17, 99, seq}, l1_auxiliary_payload(spec));
}
Bytes l1_imu_frame(const std::array<float, 4>& q, const std::array<float, 3>& gyro,
                   const std::array<float, 3>& acc, std::uint16_t packet_id, std::uint8_t seq) {
  return mavlink_frame({19, 110, seq}, l1_imu_payload(q, gyro, acc, packet_id));
}

Bytes concat(std::initializer_list<std::span<const std::uint8_t>> parts) {
  Bytes out;
  for (const auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

}  // namespace unitree_test
