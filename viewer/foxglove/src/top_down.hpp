// SPDX-License-Identifier: Apache-2.0
// A LiDAR frame seen from above as an RGB raster, for the built-in page: the sensor in the
// middle, forward (+y for Hesai, see sim/lidar_point.hpp) up, range rings every 10 m, each point
// coloured by its height or its intensity. Drawn on the server, so the page is an <img>.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "sim/layout.hpp"

namespace sim::foxglove {

enum class ColorBy { height, intensity };

struct Rgb {
  std::uint8_t r, g, b;
};
// Google's Turbo colour map: t from 0 (dark blue) to 1 (dark red), clamped.
Rgb turbo(float t);

struct TopDownOptions {
  ColorBy color = ColorBy::height;
  float range_m = 0.0f;      // half the width of the view; 0: fit 95 % of the points
  std::uint32_t size_px = 640;
};

struct TopDownImage {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> rgb;  // width × height × 3
  std::uint64_t points_drawn = 0;
  float range_m = 0;       // half the width of the view as drawn
  float ring_step_m = 0;   // distance between range rings
  float colour_low = 0;    // the value (height in m, or intensity) drawn dark blue…
  float colour_high = 0;   // …and the one drawn dark red
};

// Draws the frame; points outside the view or with non-finite coordinates are left out.
// Intensity colouring falls back to height for xyz32 frames, which have none.
void render_top_down(const PointLayout& layout, std::span<const std::byte> frame,
                     const TopDownOptions& options, TopDownImage& out);

}  // namespace sim::foxglove
