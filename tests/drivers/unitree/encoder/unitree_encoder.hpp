// SPDX-License-Identifier: Apache-2.0
// A test-only encoder for Unitree L1/L2 wire bytes, written from the official protocol headers
// (unitreerobotics/unilidar_sdk2 and unilidar_sdk, BSD-3-Clause; docs/unitree.md) and
// deliberately sharing no code with the decoder (its own bitwise CRCs, its own offsets), so a
// mistake in one shows up against the other.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace unitree_test {

using Bytes = std::vector<std::uint8_t>;

// ---- L2 (reference §7) ----------------------------------------------------------------------

std::uint32_t reference_crc32(std::span<const std::uint8_t> bytes);

// Header (magic 55 AA 05 0A, type, size) + data + tail (CRC-32 of the data only, msg_type_check,
// reserve, 00 FF).
Bytes l2_packet(std::uint32_t type, std::span<const std::uint8_t> data);

struct L2PointSpec {
  std::uint32_t seq = 0;
  std::uint32_t stamp_sec = 0;
  std::uint32_t stamp_nsec = 0;
  float a_axis_dist = 0, b_axis_dist = 0;
  float theta_angle_bias = 0, alpha_angle_bias = 0, beta_angle = 0, xi_angle = 0;
  float range_bias = 0, range_scale = 0.001F;
  float com_horizontal_angle_start = 0, com_horizontal_angle_step = 0;
  float scan_period = 0.1F, range_min = 0.0F, range_max = 100.0F;
  float angle_min = 0, angle_increment = 0, time_increment = 0;
  std::uint32_t point_num = 300;
  std::array<std::uint16_t, 300> ranges{};
  std::array<std::uint8_t, 300> intensities{};
};
Bytes l2_point_packet(const L2PointSpec& spec);  // 1044 B, type 102

// A 2D-mode packet (type 103, 5536 B; reference §7.1 "2D packet"): DataInfo and calibration as
// in 3D packets, then scan_period 96, range_min 100, range_max 104, angle_min 108,
// angle_increment 112, time_increment 116, point_num 120, ranges 124, intensities 3724.
struct L2Point2dSpec {
  std::uint32_t seq = 0;
  float a_axis_dist = 0, alpha_angle_bias = 0, range_bias = 0, range_scale = 0.001F;
  float range_min = 0.0F, range_max = 100.0F;
  float angle_min = 0, angle_increment = 0, time_increment = 0;
  std::uint32_t point_num = 1800;
  std::vector<std::uint16_t> ranges = std::vector<std::uint16_t>(1800);
  std::vector<std::uint8_t> intensities = std::vector<std::uint8_t>(1800);
};
Bytes l2_2d_packet(const L2Point2dSpec& spec);

struct L2ImuSpec {
  std::uint32_t seq = 0;
  std::uint32_t stamp_sec = 0;
  std::uint32_t stamp_nsec = 0;
  // In the order on the wire: (w, x, y, z), as real L2 units send it (the vendor example's
  // (x, y, z, w) label is wrong; see docs/unitree.md).
  std::array<float, 4> quaternion_wxyz{1, 0, 0, 0};
  std::array<float, 3> angular_velocity{};
  std::array<float, 3> linear_acceleration{};
};
Bytes l2_imu_packet(const L2ImuSpec& spec);  // 80 B, type 104

// A RoboSense MSOP-like packet: same first four bytes as an L2 packet, then 5A A5 50 A0.
Bytes robosense_packet();

// ---- L1 MAVLink v2 (reference §8) -----------------------------------------------------------

struct MavlinkSpec {
  std::uint32_t msgid = 0;
  std::uint8_t crc_extra = 0;
  std::uint8_t seq = 0;
  std::uint8_t sysid = 1;
  std::uint8_t compid = 1;
  bool trim = true;    // strip trailing zero bytes of the payload, as MAVLink v2 senders do
  bool signed_frame = false;
};
Bytes mavlink_frame(const MavlinkSpec& spec, std::span<const std::uint8_t> full_payload);

struct L1AuxSpec {
  std::uint32_t sys_rotation_period = 0, com_rotation_period = 0;
  float com_horizontal_angle_start = 0;  // deg
  float com_horizontal_angle_step = 0;   // deg per packet
  float sys_vertical_angle_start = 0;    // deg
  float sys_vertical_angle_span = 0;     // deg per point
  float b_axis_dist = 0;                 // mm
  float theta_angle = 0;                 // rad
  float ksi_angle = 0;                   // rad
  std::uint16_t packet_id = 0;
  std::array<std::uint8_t, 120> reflect{};
};
Bytes l1_distance_payload(std::uint16_t packet_id, const std::array<std::uint16_t, 120>& ranges);
Bytes l1_auxiliary_payload(const L1AuxSpec& spec);
Bytes l1_imu_payload(const std::array<float, 4>& q, const std::array<float, 3>& gyro,
                     const std::array<float, 3>& acc, std::uint16_t packet_id);

// Whole frames with the CRC_EXTRA of each message (16: 74, 17: 99, 19: 110).
Bytes l1_distance_frame(std::uint16_t packet_id, const std::array<std::uint16_t, 120>& ranges,
                        std::uint8_t seq = 0);
Bytes l1_auxiliary_frame(const L1AuxSpec& spec, std::uint8_t seq = 0);
Bytes l1_imu_frame(const std::array<float, 4>& q, const std::array<float, 3>& gyro,
                   const std::array<float, 3>& acc, std::uint16_t packet_id, std::uint8_t seq = 0);

// Concatenation helper.
Bytes concat(std::initializer_list<std::span<const std::uint8_t>> parts);

}  // namespace unitree_test
