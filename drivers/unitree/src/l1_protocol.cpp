// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/l1_protocol.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim/unitree/bytes.hpp"

namespace sim::unitree::l1 {
namespace {
constexpr double kDegToRad = std::numbers::pi / 180.0;
// See l2_protocol.cpp: rejects corrupt geometry and keeps the float conversion in range.
bool plausible(double v) noexcept { return std::isfinite(v) && std::fabs(v) < 1.0e4; }
}

std::optional<DistancePacket> parse_distance(std::span<const std::uint8_t> p) noexcept {
  if (p.size() < 246) return std::nullopt;
  DistancePacket d;
  d.packet_id = le::u16(p, 0);
  d.packet_cnt = le::u16(p, 2);
  d.payload_size = le::u16(p, 4);
  for (std::size_t j = 0; j < kPointsPerPacket; ++j) d.ranges_mm[j] = le::u16(p, 6 + 2 * j);
  return d;
}

std::optional<AuxiliaryPacket> parse_auxiliary(std::span<const std::uint8_t> p) noexcept {
  if (p.size() < 209) return std::nullopt;
  // MAVLink orders fields by size, so these offsets are not the struct order of the SDK.
  AuxiliaryPacket a;
  a.sys_rotation_period_us = le::u32(p, 12);
  a.com_rotation_period_us = le::u32(p, 16);
  a.com_horizontal_angle_start_deg = le::f32(p, 20);
  a.com_horizontal_angle_step_deg = le::f32(p, 24);
  a.sys_vertical_angle_start_deg = le::f32(p, 28);
  a.sys_vertical_angle_span_deg = le::f32(p, 32);
  a.b_axis_dist_mm = le::f32(p, 72);
  a.theta_angle_rad = le::f32(p, 76);
  a.ksi_angle_rad = le::f32(p, 80);
  a.packet_id = le::u16(p, 84);
  for (std::size_t j = 0; j < kPointsPerPacket; ++j) {
    a.reflect[j] = p[89 + j];
  }
  return a;
}

std::optional<ImuSample> parse_imu(std::span<const std::uint8_t> p) noexcept {
  if (p.size() < 42) return std::nullopt;
  ImuSample s;
  // Taken as (x, y, z, w), the order the vendor labels. Unlike the L2's (whose real samples show
  // (w, x, y, z)), no public L1 sample settles it: undetermined (docs/unitree.md).
  for (std::size_t i = 0; i < 4; ++i) s.quaternion[i] = le::f32(p, 4 * i);
  for (std::size_t i = 0; i < 3; ++i) {
    s.angular_velocity[i] = le::f32(p, 16 + 4 * i);
    s.linear_acceleration[i] = le::f32(p, 28 + 4 * i);
  }
  s.seq = le::u16(p, 40);
  return s;
}

DecodeResult decode_points(const DistancePacket& d, const AuxiliaryPacket& a,
                          const DecodeLimits& limits, std::uint32_t base_offset_ns,
                          std::uint32_t point_period_ns, std::span<LidarPoint> out) noexcept {
  // Symbols as in the L1 SDK: θ and ξ tilt the mirror axis, β is the horizontal (yaw) angle.
  const double sin_theta = std::sin(double{a.theta_angle_rad});
  const double cos_theta = std::cos(double{a.theta_angle_rad});
  const double sin_ksi = std::sin(double{a.ksi_angle_rad});
  const double cos_ksi = std::cos(double{a.ksi_angle_rad});
  const double b_axis = double{a.b_axis_dist_mm} / 1000.0;
  DecodeResult result;
  for (std::size_t j = 0; j < kPointsPerPacket; ++j) {
    if (d.ranges_mm[j] == 0) continue;
    const double r = 0.001 * d.ranges_mm[j];
    if (!(r >= limits.range_min_m && r <= limits.range_max_m)) continue;
    const double jd = static_cast<double>(j);
    const double alpha =
        (double{a.sys_vertical_angle_start_deg} + jd * a.sys_vertical_angle_span_deg) * kDegToRad;
    const double beta = (double{a.com_horizontal_angle_start_deg} + double{limits.yaw_bias_deg} +
                         jd * double{a.com_horizontal_angle_step_deg} / kPointsPerPacket) *
                        kDegToRad;
    const double sin_alpha = std::sin(alpha);
    const double cos_alpha = std::cos(alpha);
    const double big_a = (-cos_theta * sin_ksi + sin_theta * sin_alpha * cos_ksi) * r + b_axis;
    const double big_b = cos_alpha * cos_ksi * r;
    const double x = std::cos(beta) * big_a - std::sin(beta) * big_b;
    const double y = std::sin(beta) * big_a + std::cos(beta) * big_b;
    const double z = (sin_theta * sin_ksi + cos_theta * sin_alpha * cos_ksi) * r + kZBias;
    if (!plausible(x) || !plausible(y) || !plausible(z)) continue;
    if (result.written == out.size()) {
      ++result.overflow;
      continue;
    }
    LidarPoint& pt = out[result.written++];
    pt.x = static_cast<float>(x);
    pt.y = static_cast<float>(y);
    pt.z = static_cast<float>(z);
    pt.intensity = static_cast<float>(a.reflect[j]);
    const std::uint64_t t = std::uint64_t{base_offset_ns} + j * std::uint64_t{point_period_ns};
    pt.time_offset_ns = static_cast<std::uint32_t>(std::min<std::uint64_t>(t, 0xFFFFFFFFU));
    pt.ring = 0;
    pt.return_index = 0;
    pt.reserved = 0;
  }
  return result;
}

}  // namespace sim::unitree::l1
