// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/l2_protocol.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/unitree/bytes.hpp"

namespace sim::unitree::l2 {
namespace {
// A coordinate no LiDAR can measure means corrupt calibration fields (which the CRC does not
// catch if the sensor sent them); it also keeps the float conversion below in range.
bool plausible(double v) noexcept { return std::isfinite(v) && std::fabs(v) < 1.0e4; }
}  // namespace

std::optional<std::size_t> expected_size(std::uint32_t packet_type) noexcept {
  // Data sizes from the field lists (reference §7 "Sizes"), plus 24 B of header and tail.
  switch (packet_type) {
    case user_cmd: return 32;
    case ack: return 40;
    case point_3d: return kPoint3dSize;
    case point_2d: return 5536;
    case imu: return kImuSize;
    case version: return 104;
    case time_stamp: return 32;
    case work_mode: return 28;
    case ip_config: return 44;
    case mac_config: return 32;
    default: return std::nullopt;
  }
}

std::optional<PointPacketHeader> parse_point_header(std::span<const std::uint8_t> p) noexcept {
  if (p.size() != kPoint3dSize || le::u32(p, 4) != point_3d) return std::nullopt;
  namespace o = point3d;
  PointPacketHeader h;
  h.seq = le::u32(p, o::seq);
  h.stamp_ns = std::int64_t{le::u32(p, o::stamp_sec)} * 1'000'000'000 + le::u32(p, o::stamp_nsec);
  h.a_axis_dist = le::f32(p, o::a_axis_dist);
  h.b_axis_dist = le::f32(p, o::b_axis_dist);
  h.theta_angle_bias = le::f32(p, o::theta_angle_bias);
  h.alpha_angle_bias = le::f32(p, o::alpha_angle_bias);
  h.beta_angle = le::f32(p, o::beta_angle);
  h.xi_angle = le::f32(p, o::xi_angle);
  h.range_bias = le::f32(p, o::range_bias);
  h.range_scale = le::f32(p, o::range_scale);
  h.horizontal_angle_start = le::f32(p, o::horizontal_angle_start);
  h.horizontal_angle_step = le::f32(p, o::horizontal_angle_step);
  h.scan_period = le::f32(p, o::scan_period);
  h.range_min = le::f32(p, o::range_min);
  h.range_max = le::f32(p, o::range_max);
  h.angle_min = le::f32(p, o::angle_min);
  h.angle_increment = le::f32(p, o::angle_increment);
  h.time_increment = le::f32(p, o::time_increment);
  h.point_num = le::u32(p, o::point_num);
  if (h.point_num > kPointsPerPacket) return std::nullopt;
  return h;
}

std::optional<PointPacketHeader> parse_2d_header(std::span<const std::uint8_t> p) noexcept {
  if (p.size() != kPoint2dSize || le::u32(p, 4) != point_2d) return std::nullopt;
  namespace o = point3d;  // DataInfo and calibration sit where they do in 3D packets
  namespace t = point2d;
  PointPacketHeader h;
  h.seq = le::u32(p, o::seq);
  h.stamp_ns = std::int64_t{le::u32(p, o::stamp_sec)} * 1'000'000'000 + le::u32(p, o::stamp_nsec);
  h.a_axis_dist = le::f32(p, o::a_axis_dist);
  h.b_axis_dist = le::f32(p, o::b_axis_dist);
  h.theta_angle_bias = le::f32(p, o::theta_angle_bias);
  h.alpha_angle_bias = le::f32(p, o::alpha_angle_bias);
  h.beta_angle = le::f32(p, o::beta_angle);
  h.xi_angle = le::f32(p, o::xi_angle);
  h.range_bias = le::f32(p, o::range_bias);
  h.range_scale = le::f32(p, o::range_scale);
  h.scan_period = le::f32(p, t::scan_period);
  h.range_min = le::f32(p, t::range_min);
  h.range_max = le::f32(p, t::range_max);
  h.angle_min = le::f32(p, t::angle_min);
  h.angle_increment = le::f32(p, t::angle_increment);
  h.time_increment = le::f32(p, t::time_increment);
  h.point_num = le::u32(p, t::point_num);
  if (h.point_num > kPointsPer2dPacket) return std::nullopt;
  return h;
}

DecodeResult decode_2d_points(std::span<const std::uint8_t> p, const PointPacketHeader& h,
                              const DecodeLimits& limits, std::uint32_t base_offset_ns,
                              std::span<LidarPoint> out) noexcept {
  const double r_min = std::max(double{h.range_min}, double{limits.range_min_m});
  const double r_max = std::min(double{h.range_max}, double{limits.range_max_m});
  const std::size_t count = std::min<std::size_t>(h.point_num, kPointsPer2dPacket);
  DecodeResult result;
  for (std::size_t j = 0; j < count; ++j) {
    const std::uint16_t raw = le::u16(p, point2d::ranges + 2 * j);
    if (raw < 1) continue;
    const double r = double{h.range_scale} * (static_cast<double>(raw) + double{h.range_bias});
    if (!(r >= r_min && r <= r_max)) continue;
    const double jd = static_cast<double>(j);
    const double alpha = double{h.angle_min} + double{h.alpha_angle_bias} + jd * h.angle_increment;
    const double y = std::cos(alpha) * r;
    const double z = std::sin(alpha) * r + h.a_axis_dist;
    if (!plausible(y) || !plausible(z)) continue;
    if (result.written == out.size()) {
      ++result.overflow;
      continue;
    }
    const double t = static_cast<double>(base_offset_ns) + jd * double{h.time_increment} * 1e9;
    LidarPoint& pt = out[result.written++];
    pt.x = 0.0F;
    pt.y = static_cast<float>(y);
    pt.z = static_cast<float>(z);
    pt.intensity = static_cast<float>(p[point2d::intensities + j]);
    pt.time_offset_ns = (t >= 0.0 && t < 4.0e9) ? static_cast<std::uint32_t>(t) : base_offset_ns;
    pt.ring = 0;
    pt.return_index = 0;
    pt.reserved = 0;
  }
  return result;
}

DecodeResult decode_points(std::span<const std::uint8_t> p, const PointPacketHeader& h,
                          const DecodeLimits& limits, std::uint32_t base_offset_ns,
                          std::span<LidarPoint> out) noexcept {
  // Double precision inside, so the angle accumulation j·step does not lose the last digits.
  const double sin_beta = std::sin(double{h.beta_angle});
  const double cos_beta = std::cos(double{h.beta_angle});
  const double sin_xi = std::sin(double{h.xi_angle});
  const double cos_xi = std::cos(double{h.xi_angle});
  const double r_min = std::max(double{h.range_min}, double{limits.range_min_m});
  const double r_max = std::min(double{h.range_max}, double{limits.range_max_m});
  const std::size_t count = std::min<std::size_t>(h.point_num, kPointsPerPacket);
  DecodeResult result;
  for (std::size_t j = 0; j < count; ++j) {
    const std::uint16_t raw = le::u16(p, point3d::ranges + 2 * j);
    if (raw < 1) continue;
    const double r = double{h.range_scale} * (static_cast<double>(raw) + double{h.range_bias});
    if (!(r >= r_min && r <= r_max)) continue;  // also drops NaN
    const double jd = static_cast<double>(j);
    const double alpha = double{h.angle_min} + double{h.alpha_angle_bias} + jd * h.angle_increment;
    const double theta = double{h.horizontal_angle_start} + double{h.theta_angle_bias} +
                         jd * h.horizontal_angle_step;
    const double sin_alpha = std::sin(alpha);
    const double cos_alpha = std::cos(alpha);
    const double a = (-cos_beta * sin_xi + sin_beta * cos_xi * sin_alpha) * r + h.b_axis_dist;
    const double b = cos_alpha * cos_xi * r;
    const double c = (sin_beta * sin_xi + cos_beta * cos_xi * sin_alpha) * r;
    const double x = std::cos(theta) * a - std::sin(theta) * b;
    const double y = std::sin(theta) * a + std::cos(theta) * b;
    const double z = c + h.a_axis_dist;
    if (!plausible(x) || !plausible(y) || !plausible(z)) continue;
    if (result.written == out.size()) {
      ++result.overflow;
      continue;
    }
    const double t = static_cast<double>(base_offset_ns) + jd * double{h.time_increment} * 1e9;
    LidarPoint& pt = out[result.written++];
    pt.x = static_cast<float>(x);
    pt.y = static_cast<float>(y);
    pt.z = static_cast<float>(z);
    pt.intensity = static_cast<float>(p[point3d::intensities + j]);
    pt.time_offset_ns = (t >= 0.0 && t < 4.0e9) ? static_cast<std::uint32_t>(t) : base_offset_ns;
    pt.ring = 0;  // one laser: Unitree has no rings
    pt.return_index = 0;
    pt.reserved = 0;
  }
  return result;
}

std::optional<ImuSample> parse_imu(std::span<const std::uint8_t> p) noexcept {
  if (p.size() != kImuSize || le::u32(p, 4) != imu) return std::nullopt;
  namespace o = imu_packet;
  ImuSample s;
  s.seq = le::u32(p, o::seq);
  s.stamp_ns = std::int64_t{le::u32(p, o::stamp_sec)} * 1'000'000'000 + le::u32(p, o::stamp_nsec);
  // On the wire (w, x, y, z), whatever the vendor example's label says: decoded real samples
  // agree with gravity only in this order (docs/unitree.md). Published as (x, y, z, w).
  s.quaternion[3] = le::f32(p, o::quaternion);
  for (std::size_t i = 0; i < 3; ++i) s.quaternion[i] = le::f32(p, o::quaternion + 4 * (i + 1));
  for (std::size_t i = 0; i < 3; ++i) {
    s.angular_velocity[i] = le::f32(p, o::angular_velocity + 4 * i);
    s.linear_acceleration[i] = le::f32(p, o::linear_acceleration + 4 * i);
  }
  return s;
}

}  // namespace sim::unitree::l2
