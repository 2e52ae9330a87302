// SPDX-License-Identifier: Apache-2.0
#include "projection.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "top_down.hpp"

namespace sim::foxglove {
namespace {

// Deeper chains of mountings than this are taken for a loop.
constexpr int kMaxFrameDepth = 32;
// Points nearer than this in front of the camera are not drawn (the model breaks down at 0).
constexpr double kMinDepthM = 0.1;

using Vec3 = std::array<double, 3>;

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// The pose of `frame` in the root of its tree, and that root's name.
std::optional<std::pair<Pose, std::string>> pose_in_root(
    const std::map<std::string, const FrameTransform*>& by_child, std::string frame) {
  Pose pose;
  for (int depth = 0; depth < kMaxFrameDepth; ++depth) {
    const auto it = by_child.find(frame);
    if (it == by_child.end()) return std::make_pair(pose, frame);
    pose = Pose::of(it->second->mounting) * pose;
    frame = it->second->parent;
  }
  return std::nullopt;
}

// The distortion of a normalised image point (x, y) = (X/Z, Y/Z), as OpenCV and ROS apply it.
std::array<double, 2> distort(const CameraCalibration& c, double x, double y) {
  auto d = [&](std::size_t i) { return i < c.d.size() ? c.d[i] : 0.0; };
  if (c.distortion_model == "equidistant") {  // Kannala-Brandt: k1..k4 on the angle
    const double r = std::hypot(x, y);
    if (r < 1e-12) return {x, y};
    const double theta = std::atan(r), t2 = theta * theta;
    const double theta_d =
        theta * (1 + d(0) * t2 + d(1) * t2 * t2 + d(2) * t2 * t2 * t2 + d(3) * t2 * t2 * t2 * t2);
    return {x * theta_d / r, y * theta_d / r};
  }
  if (c.distortion_model != "plumb_bob" && c.distortion_model != "rational_polynomial") {
    return {x, y};  // a model this view does not know: drawn undistorted
  }
  // k1 k2 p1 p2 k3 [k4 k5 k6]
  const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double radial =
      (1 + d(0) * r2 + d(1) * r4 + d(4) * r6) / (1 + d(5) * r2 + d(6) * r4 + d(7) * r6);
  return {x * radial + 2 * d(2) * x * y + d(3) * (r2 + 2 * x * x),
          y * radial + d(2) * (r2 + 2 * y * y) + 2 * d(3) * x * y};
}

}  // namespace

Vec3 Pose::apply(const Vec3& p) const noexcept {
  // p + 2w (q × p) + 2 q × (q × p), with q the vector part.
  const Vec3 q{rotation[0], rotation[1], rotation[2]};
  const double w = rotation[3];
  const Vec3 t = cross(q, p);
  const Vec3 u{2 * t[0], 2 * t[1], 2 * t[2]};
  const Vec3 v = cross(q, u);
  return {p[0] + w * u[0] + v[0] + translation[0], p[1] + w * u[1] + v[1] + translation[1],
          p[2] + w * u[2] + v[2] + translation[2]};
}

Pose Pose::inverse() const noexcept {
  Pose inv;
  inv.rotation = {-rotation[0], -rotation[1], -rotation[2], rotation[3]};
  const Vec3 back = inv.apply(translation);
  inv.translation = {-back[0], -back[1], -back[2]};
  return inv;
}

Pose operator*(const Pose& a, const Pose& b) noexcept {
  const auto& p = a.rotation;
  const auto& q = b.rotation;
  Pose out;
  out.rotation = {p[3] * q[0] + p[0] * q[3] + p[1] * q[2] - p[2] * q[1],
                  p[3] * q[1] - p[0] * q[2] + p[1] * q[3] + p[2] * q[0],
                  p[3] * q[2] + p[0] * q[1] - p[1] * q[0] + p[2] * q[3],
                  p[3] * q[3] - p[0] * q[0] - p[1] * q[1] - p[2] * q[2]};
  out.translation = a.apply(b.translation);
  return out;
}

Expected<Pose> pose_between(const std::vector<FrameTransform>& mountings, std::string_view from,
                            std::string_view to) {
  std::map<std::string, const FrameTransform*> by_child;
  for (const FrameTransform& m : mountings) by_child.emplace(m.child, &m);
  const auto source = pose_in_root(by_child, std::string(from));
  const auto target = pose_in_root(by_child, std::string(to));
  if (!source || !target) {
    return Error{ErrorCode::invalid_argument,
                 "the mountings of " + std::string(from) + " and " + std::string(to) +
                     " form a loop; give each sensor one parent frame."};
  }
  if (source->second != target->second) {
    return Error{ErrorCode::not_found,
                 "no chain of mountings joins " + std::string(from) + " (under " +
                     source->second + ") and " + std::string(to) + " (under " + target->second +
                     "); give both sensors a mounting in the same parent frame."};
  }
  return target->first.inverse() * source->first;
}

std::optional<std::array<float, 2>> project_to_pixel(const CameraCalibration& c,
                                                     std::uint32_t image_width,
                                                     std::uint32_t image_height,
                                                     const Vec3& point) {
  if (!(point[2] > kMinDepthM)) return std::nullopt;
  // K, or P's left 3×3 when the file had no K.
  const bool has_k = c.k[0] != 0 && c.k[4] != 0;
  const double fx = has_k ? c.k[0] : c.p[0], skew = has_k ? c.k[1] : c.p[1];
  const double cx = has_k ? c.k[2] : c.p[2], fy = has_k ? c.k[4] : c.p[5];
  const double cy = has_k ? c.k[5] : c.p[6];
  if (fx == 0 || fy == 0) return std::nullopt;
  const double x = point[0] / point[2], y = point[1] / point[2];
  // Far outside the calibrated field a distortion polynomial folds back into the image: only
  // points whose undistorted pixel is near the picture are distorted and drawn. Not for the
  // equidistant (fisheye) model, whose angle stays below 90 degrees in front of the camera while
  // its undistorted pixel grows like tan: that gate culled a wide lens's periphery (review turn
  // 4 L4); the picture's bounds below still apply.
  const double w = c.width > 0 ? c.width : image_width, h = c.height > 0 ? c.height : image_height;
  const double u0 = fx * x + cx, v0 = fy * y + cy;
  if (c.distortion_model != "equidistant" &&
      (u0 < -0.5 * w || u0 > 1.5 * w || v0 < -0.5 * h || v0 > 1.5 * h)) {
    return std::nullopt;
  }
  const auto [xd, yd] = distort(c, x, y);
  double u = fx * xd + skew * yd + cx;
  double v = fy * yd + cy;
  // The calibration is of the full sensor; the image may be binned and cut (ROS's convention).
  u = (u - c.roi.x_offset) / std::max(1u, c.binning_x);
  v = (v - c.roi.y_offset) / std::max(1u, c.binning_y);
  if (!(u >= 0 && v >= 0 && u < image_width && v < image_height)) return std::nullopt;
  return std::array<float, 2>{static_cast<float>(u), static_cast<float>(v)};
}

ProjectionResult draw_projected_points(const PointLayout& layout, std::span<const std::byte> frame,
                                       const Pose& lidar_to_camera,
                                       const CameraCalibration& calibration, std::uint32_t width,
                                       std::uint32_t height, std::span<std::uint8_t> bgr) {
  ProjectionResult result;
  const std::size_t stride = layout.point_size;
  if (stride < 12 || bgr.size() < std::size_t{width} * height * 3) return result;
  struct Dot {
    float u, v, depth;
  };
  std::vector<Dot> dots;
  const std::size_t count = frame.size() / stride;
  for (std::size_t i = 0; i < count; ++i) {
    float xyz[3];
    std::memcpy(xyz, frame.data() + i * stride, sizeof xyz);
    if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) continue;
    if (xyz[0] == 0 && xyz[1] == 0 && xyz[2] == 0) continue;  // no return
    ++result.points;
    const Vec3 p = lidar_to_camera.apply({xyz[0], xyz[1], xyz[2]});
    if (const auto pixel = project_to_pixel(calibration, width, height, p)) {
      dots.push_back({(*pixel)[0], (*pixel)[1], static_cast<float>(p[2])});
    }
  }
  result.projected = dots.size();
  if (dots.empty()) return result;
  // Farther first, so nearer points are drawn over them; colours span the 2nd–98th percentile.
  std::sort(dots.begin(), dots.end(), [](const Dot& a, const Dot& b) { return a.depth > b.depth; });
  result.nearest_m = dots[dots.size() - 1 - dots.size() * 2 / 100].depth;
  result.farthest_m = std::max(dots[dots.size() * 2 / 100].depth, result.nearest_m + 0.1f);
  const int dot = width >= 1280 ? 3 : 2;
  for (const Dot& d : dots) {
    // Turbo from its bright blue on: its darkest blues would vanish in a dark picture.
    const float t = std::clamp((d.depth - result.nearest_m) / (result.farthest_m - result.nearest_m), 0.0f, 1.0f);
    const Rgb c = turbo(0.15f + 0.85f * t);
    for (int dy = 0; dy < dot; ++dy) {
      for (int dx = 0; dx < dot; ++dx) {
        const auto x = static_cast<std::uint32_t>(d.u) + static_cast<std::uint32_t>(dx);
        const auto y = static_cast<std::uint32_t>(d.v) + static_cast<std::uint32_t>(dy);
        if (x >= width || y >= height) continue;
        std::uint8_t* px = bgr.data() + (std::size_t{y} * width + x) * 3;
        px[0] = c.b;
        px[1] = c.g;
        px[2] = c.r;
      }
    }
  }
  return result;
}

}  // namespace sim::foxglove
