// SPDX-License-Identifier: Apache-2.0
// Unitree L2 packet layout, from the field lists of the official protocol header
// (unitreerobotics/unilidar_sdk2, BSD-3-Clause; docs/unitree.md), corrected where it is wrong:
// its size comments (a 3D point packet is 1044 B, an IMU packet 80 B), and the CRC-32 covers the
// data bytes only (offset 12 … packet_size − 13), not the header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "sim/lidar_point.hpp"
#include "sim/unitree/imu.hpp"

namespace sim::unitree::l2 {

inline constexpr std::uint8_t kMagic[4] = {std::uint8_t{0x55}, std::uint8_t{0xAA}, std::uint8_t{0x05},
                                        std::uint8_t{0x0A}};
// RoboSense MSOP packets begin with the same four bytes, then 5A A5 50 A0.
inline constexpr std::uint8_t kRoboSenseTag[4] = {std::uint8_t{0x5A}, std::uint8_t{0xA5}, std::uint8_t{0x50},
                                               std::uint8_t{0xA0}};

inline constexpr std::size_t kHeaderSize = 12;  // magic, packet_type, packet_size
inline constexpr std::size_t kTailSize = 12;    // crc32, msg_type_check, reserve[2], tail[2]
// Bound on packets of types this decoder does not know (their size is taken from the header).
inline constexpr std::size_t kMaxPacketSize = 8192;

enum PacketType : std::uint32_t {
  user_cmd = 100,
  ack = 101,
  point_3d = 102,
  point_2d = 103,
  imu = 104,
  version = 105,
  time_stamp = 106,
  work_mode = 107,
  ip_config = 108,
  mac_config = 109,
  command = 2000,
  param_data = 2001,
};

// The total size a packet of a known type must have; nullopt for types not listed in §7.
std::optional<std::size_t> expected_size(std::uint32_t packet_type) noexcept;

inline constexpr std::size_t kPoint3dSize = 1044;
inline constexpr std::size_t kPoint2dSize = 5536;
inline constexpr std::size_t kPointsPer2dPacket = 1800;
inline constexpr std::size_t kImuSize = 80;
inline constexpr std::size_t kPointsPerPacket = 300;

// Absolute offsets in a type-102 packet.
namespace point3d {
inline constexpr std::size_t seq = 12;
inline constexpr std::size_t payload_size = 16;
inline constexpr std::size_t stamp_sec = 20;
inline constexpr std::size_t stamp_nsec = 24;
inline constexpr std::size_t a_axis_dist = 64;
inline constexpr std::size_t b_axis_dist = 68;
inline constexpr std::size_t theta_angle_bias = 72;
inline constexpr std::size_t alpha_angle_bias = 76;
inline constexpr std::size_t beta_angle = 80;
inline constexpr std::size_t xi_angle = 84;
inline constexpr std::size_t range_bias = 88;
inline constexpr std::size_t range_scale = 92;
inline constexpr std::size_t horizontal_angle_start = 96;
inline constexpr std::size_t horizontal_angle_step = 100;
inline constexpr std::size_t scan_period = 104;
inline constexpr std::size_t range_min = 108;
inline constexpr std::size_t range_max = 112;
inline constexpr std::size_t angle_min = 116;
inline constexpr std::size_t angle_increment = 120;
inline constexpr std::size_t time_increment = 124;
inline constexpr std::size_t point_num = 128;
inline constexpr std::size_t ranges = 132;       // u16[300], mm
inline constexpr std::size_t intensities = 732;  // u8[300]
inline constexpr std::size_t crc = 1032;
}  // namespace point3d

// Absolute offsets in a type-103 (2D mode) packet where they differ from type 102.
namespace point2d {
inline constexpr std::size_t scan_period = 96;
inline constexpr std::size_t range_min = 100;
inline constexpr std::size_t range_max = 104;
inline constexpr std::size_t angle_min = 108;
inline constexpr std::size_t angle_increment = 112;
inline constexpr std::size_t time_increment = 116;
inline constexpr std::size_t point_num = 120;
inline constexpr std::size_t ranges = 124;        // u16[1800], mm
inline constexpr std::size_t intensities = 3724;  // u8[1800]
}  // namespace point2d

namespace imu_packet {
inline constexpr std::size_t seq = 12;
inline constexpr std::size_t stamp_sec = 20;
inline constexpr std::size_t stamp_nsec = 24;
inline constexpr std::size_t quaternion = 28;
inline constexpr std::size_t angular_velocity = 44;
inline constexpr std::size_t linear_acceleration = 56;
}  // namespace imu_packet

// The geometry every point packet carries (calibration travels in each packet).
struct PointPacketHeader {
  std::uint32_t seq = 0;
  std::int64_t stamp_ns = 0;  // sensor clock: info.stamp.sec·1e9 + nsec
  float a_axis_dist = 0, b_axis_dist = 0;
  float theta_angle_bias = 0, alpha_angle_bias = 0, beta_angle = 0, xi_angle = 0;
  float range_bias = 0, range_scale = 0;
  float horizontal_angle_start = 0, horizontal_angle_step = 0;
  float scan_period = 0, range_min = 0, range_max = 0;
  float angle_min = 0, angle_increment = 0, time_increment = 0;
  std::uint32_t point_num = 0;
};

// Reads the fields of a framed, CRC-checked type-102 packet. nullopt when the packet is not one
// (wrong size/type) or its point count exceeds 300.
std::optional<PointPacketHeader> parse_point_header(std::span<const std::uint8_t> packet) noexcept;

// The same for a type-103 (2D) packet: no horizontal angle fields; point_num ≤ 1800.
std::optional<PointPacketHeader> parse_2d_header(std::span<const std::uint8_t> packet) noexcept;

struct DecodeLimits {
  float range_min_m = 0.0F;   // user limits, applied on top of the packet's own
  float range_max_m = 1.0e9F;
};

struct DecodeResult {
  std::size_t written = 0;   // points stored in `out`
  std::size_t overflow = 0;  // valid points that did not fit in `out`
};

// Converts the packet's points with the official range/angle→XYZ formulas into `out`
// (at most out.size() points; zero, out-of-range and implausible results are skipped).
// time_offset_ns is `base_offset_ns + j·time_increment`.
DecodeResult decode_points(std::span<const std::uint8_t> packet, const PointPacketHeader& header,
                          const DecodeLimits& limits, std::uint32_t base_offset_ns,
                          std::span<LidarPoint> out) noexcept;

// 2D mode (reference §7.2): x = 0, y = cosα·r, z = sinα·r + a_axis_dist, with α and r as for
// 3D packets.
DecodeResult decode_2d_points(std::span<const std::uint8_t> packet, const PointPacketHeader& header,
                              const DecodeLimits& limits, std::uint32_t base_offset_ns,
                              std::span<LidarPoint> out) noexcept;

// Reads a framed, CRC-checked type-104 packet.
std::optional<ImuSample> parse_imu(std::span<const std::uint8_t> packet) noexcept;

}  // namespace sim::unitree::l2
