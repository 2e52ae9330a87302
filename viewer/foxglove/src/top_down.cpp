// SPDX-License-Identifier: Apache-2.0
#include "top_down.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace sim::foxglove {

// Google's "Turbo" colour map as its published polynomial fit: dark blue → red, readable on
// a dark background and in both colour-blind and greyscale prints.
Rgb turbo(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  const float t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
  const float r = 0.13572138f + 4.61539260f * t - 42.66032258f * t2 + 132.13108234f * t3 -
                  152.94239396f * t4 + 59.28637943f * t5;
  const float g = 0.09140261f + 2.19418839f * t + 4.84296658f * t2 - 14.18503333f * t3 +
                  4.27729857f * t4 + 2.82956604f * t5;
  const float b = 0.10667330f + 12.64194608f * t - 60.58204836f * t2 + 110.36276771f * t3 -
                  89.90310912f * t4 + 27.34824973f * t5;
  auto byte = [](float v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f); };
  return {byte(r), byte(g), byte(b)};
}

namespace {

struct PointView {
  float x, y, z, value;
};

// Reads the fields the view needs from any SIM point type (memcpy: frames need not be aligned).
bool read_point(const PointLayout& layout, const std::byte* p, ColorBy color, PointView& out) {
  float xyz[3];
  std::memcpy(xyz, p, sizeof xyz);
  float intensity = 0;
  const bool has_intensity =
      layout.type == PointType::xyzi32 || layout.type == PointType::lidar_point;
  if (has_intensity) std::memcpy(&intensity, p + 12, sizeof intensity);
  out = {xyz[0], xyz[1], xyz[2],
         color == ColorBy::intensity && has_intensity ? intensity : xyz[2]};
  return std::isfinite(out.x) && std::isfinite(out.y) && std::isfinite(out.z) &&
         std::isfinite(out.value) && (out.x != 0 || out.y != 0 || out.z != 0);
}

// The 2nd and 98th percentile of the colour values, so one stray point does not wash out the
// scale; from a sample, as the exact order does not matter for a picture.
std::pair<float, float> colour_range(std::vector<float>& values) {
  if (values.empty()) return {0.0f, 1.0f};
  const auto lo = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 2 / 100);
  const auto hi = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 98 / 100);
  std::nth_element(values.begin(), lo, values.end());
  const float low = *lo;
  std::nth_element(values.begin(), hi, values.end());
  const float high = *hi;
  return {low, high > low ? high : low + 1.0f};
}

// Where a frame's points are in memory: every `stride` bytes, `count` of them; `step` samples
// about 4096 of them for the scale computations.
struct PointSpan {
  const PointLayout& layout;
  std::span<const std::byte> frame;
  std::uint32_t stride;
  std::size_t count;
  std::size_t step;

  const std::byte* at(std::size_t i) const { return frame.data() + i * stride; }
};

// Automatic range: the 95th percentile of horizontal distance, rounded up to a nice number,
// so an indoor scan and a highway scan both fill the view.
float fitted_range(const PointSpan& points) {
  std::vector<float> distances;
  PointView v{};
  for (std::size_t i = 0; i < points.count; i += points.step) {
    if (read_point(points.layout, points.at(i), ColorBy::height, v)) distances.push_back(std::hypot(v.x, v.y));
  }
  float far = 50.0f;
  if (!distances.empty()) {
    const auto at = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() * 95 / 100);
    std::nth_element(distances.begin(), at, distances.end());
    far = *at;
  }
  float range = 5.0f;
  for (const float nice : {5.0f, 10.0f, 20.0f, 30.0f, 50.0f, 75.0f, 100.0f, 150.0f, 200.0f}) {
    range = nice;
    if (nice >= far) break;
  }
  return range;
}

// The raster being drawn, with the view's geometry: metres to pixels, the sensor in the middle.
struct Canvas {
  TopDownImage& out;
  std::uint32_t size;
  float scale;   // pixels per metre
  float centre;  // the sensor's pixel row and column

  void put(int px, int py, Rgb c) {
    if (px < 0 || py < 0 || px >= static_cast<int>(size) || py >= static_cast<int>(size)) return;
    std::uint8_t* p = &out.rgb[(std::size_t(py) * size + std::size_t(px)) * 3];
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }
};

// A dark background, range rings and the sensor's forward axis in dark grey.
void draw_background(Canvas& canvas, float range, float ring_step) {
  std::fill(canvas.out.rgb.begin(), canvas.out.rgb.end(), std::uint8_t{17});
  for (float ring = ring_step; ring <= range * 1.42f; ring += ring_step) {
    const float radius = ring * canvas.scale;
    const int steps = static_cast<int>(radius * 7.0f) + 16;
    for (int k = 0; k < steps; ++k) {
      const float a = 6.2831853f * static_cast<float>(k) / static_cast<float>(steps);
      canvas.put(static_cast<int>(canvas.centre + radius * std::cos(a)),
                 static_cast<int>(canvas.centre - radius * std::sin(a)), {60, 60, 60});
    }
  }
  for (int py = 0; py < static_cast<int>(canvas.centre); ++py) {
    canvas.put(static_cast<int>(canvas.centre), py, {45, 45, 45});
  }
}

// Every point inside the view, coloured on the scale from `low` (blue) to `high` (red); on large
// views as 2×2 squares so sparse scans stay visible. Returns how many were drawn.
std::uint64_t draw_points(Canvas& canvas, const PointSpan& points, ColorBy color, float low,
                          float high) {
  const int dot = canvas.size >= 480 ? 2 : 1;
  const auto size = static_cast<float>(canvas.size);
  std::uint64_t drawn = 0;
  PointView v{};
  for (std::size_t i = 0; i < points.count; ++i) {
    if (!read_point(points.layout, points.at(i), color, v)) continue;
    const float fx = canvas.centre + v.x * canvas.scale;
    const float fy = canvas.centre - v.y * canvas.scale;
    if (!(fx >= 0 && fy >= 0 && fx < size && fy < size)) continue;
    const Rgb colour = turbo((v.value - low) / (high - low));
    for (int dy = 0; dy < dot; ++dy) {
      for (int dx = 0; dx < dot; ++dx) canvas.put(static_cast<int>(fx) + dx, static_cast<int>(fy) + dy, colour);
    }
    ++drawn;
  }
  return drawn;
}

}  // namespace

void render_top_down(const PointLayout& layout, std::span<const std::byte> frame,
                     const TopDownOptions& options, TopDownImage& out) {
  const std::uint32_t size = std::clamp<std::uint32_t>(options.size_px, 64, 2048);
  out.width = out.height = size;
  out.rgb.resize(std::size_t{size} * size * 3);
  out.points_drawn = 0;
  const std::uint32_t stride = layout.point_size;
  const bool readable = stride >= 16 || (stride >= 12 && layout.type == PointType::xyz32);
  const std::size_t count = readable ? frame.size() / stride : 0;
  const PointSpan points{layout, frame, stride, count, std::max<std::size_t>(1, count / 4096)};

  const float range = options.range_m >= 1.0f ? options.range_m : fitted_range(points);
  out.range_m = range;
  out.ring_step_m = range <= 10.0f ? 2.0f : range <= 30.0f ? 5.0f : range <= 100.0f ? 10.0f : 50.0f;
  Canvas canvas{out, size, static_cast<float>(size) / (2.0f * range), static_cast<float>(size) / 2.0f};
  draw_background(canvas, range, out.ring_step_m);
  if (count == 0) return;

  std::vector<float> values;
  values.reserve(std::min<std::size_t>(count, 4096));
  PointView v{};
  for (std::size_t i = 0; i < count; i += points.step) {
    if (read_point(layout, points.at(i), options.color, v)) values.push_back(v.value);
  }
  const auto [low, high] = colour_range(values);
  out.colour_low = low;
  out.colour_high = high;
  out.points_drawn = draw_points(canvas, points, options.color, low, high);
  // The sensor itself: a small white cross.
  const int c = static_cast<int>(canvas.centre);
  for (int d = -4; d <= 4; ++d) {
    canvas.put(c + d, c, {255, 255, 255});
    canvas.put(c, c + d, {255, 255, 255});
  }
}

}  // namespace sim::foxglove
