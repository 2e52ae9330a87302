// SPDX-License-Identifier: Apache-2.0
// Unitree L1 MAVLink payloads (reference §8): a distance packet (msgid 16) and an auxiliary packet
// (msgid 17) with the same packet_id together make 120 points; msgid 19 is the IMU.
// Payloads arrive zero-extended to their full length from MavlinkFramer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "sim/lidar_point.hpp"
#include "sim/unitree/imu.hpp"

namespace sim::unitree::l1 {

inline constexpr std::uint32_t kMsgDistance = 16;
inline constexpr std::uint32_t kMsgAuxiliary = 17;
inline constexpr std::uint32_t kMsgTimeSync = 18;
inline constexpr std::uint32_t kMsgImu = 19;
inline constexpr std::uint32_t kMsgVersion = 13;
inline constexpr std::size_t kPointsPerPacket = 120;
// The L1's fixed height of the optical centre above the mount (the SDK's z_bias), metres.
inline constexpr double kZBias = 0.0445;

struct DistancePacket {
  std::uint16_t packet_id = 0;
  std::uint16_t packet_cnt = 0;
  std::uint16_t payload_size = 0;
  std::uint16_t ranges_mm[kPointsPerPacket] = {};
};

struct AuxiliaryPacket {
  std::uint32_t sys_rotation_period_us = 0;
  std::uint32_t com_rotation_period_us = 0;
  float com_horizontal_angle_start_deg = 0;
  float com_horizontal_angle_step_deg = 0;  // per packet (120 points)
  float sys_vertical_angle_start_deg = 0;
  float sys_vertical_angle_span_deg = 0;    // per point
  float b_axis_dist_mm = 0;
  float theta_angle_rad = 0;
  float ksi_angle_rad = 0;
  std::uint16_t packet_id = 0;
  std::uint8_t reflect[kPointsPerPacket] = {};
};

// Each takes a zero-extended payload of the message's full length; nullopt on a shorter one.
std::optional<DistancePacket> parse_distance(std::span<const std::uint8_t> payload) noexcept;
std::optional<AuxiliaryPacket> parse_auxiliary(std::span<const std::uint8_t> payload) noexcept;
std::optional<ImuSample> parse_imu(std::span<const std::uint8_t> payload) noexcept;  // stamp_ns 0

struct DecodeLimits {
  float range_min_m = 0.0F;
  float range_max_m = 1.0e9F;
  float yaw_bias_deg = 0.0F;  // the SDK's rotate_yaw_bias, default 0
};

// The SDK's XYZ formulas for one paired packet; point j gets
// time_offset_ns = base_offset_ns + j·point_period_ns.
struct DecodeResult {
  std::size_t written = 0;   // points stored in `out`
  std::size_t overflow = 0;  // valid points that did not fit in `out`
};
DecodeResult decode_points(const DistancePacket& distance, const AuxiliaryPacket& aux,
                          const DecodeLimits& limits, std::uint32_t base_offset_ns,
                          std::uint32_t point_period_ns, std::span<LidarPoint> out) noexcept;

}  // namespace sim::unitree::l1
