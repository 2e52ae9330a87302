// SPDX-License-Identifier: Apache-2.0
// What a stream's payload looks like, stored in the region header so any reader can interpret a
// frame without a side channel: raw bytes, an image viewable as cv::Mat, or an array of points.
#pragma once

#include <cstdint>
#include <string>

namespace sim {

enum class PixelFormat : std::uint32_t {
  unknown = 0,
  mono8 = 1,
  mono16 = 2,
  bgr8 = 3,
  rgb8 = 4,
  bgra8 = 5,
  rgba8 = 6,
  yuyv = 7,   // packed 4:2:2, Y0 U Y1 V
  uyvy = 8,   // packed 4:2:2, U Y0 V Y1
  bayer_rggb8 = 9,
  bayer_bggr8 = 10,
  bayer_gbrg8 = 11,
  bayer_grbg8 = 12,
  mjpeg = 13,  // compressed: size varies per frame, stride is 0
};

const char* to_string(PixelFormat format) noexcept;
// Bytes per pixel for packed formats; 0 for compressed ones.
std::uint32_t bytes_per_pixel(PixelFormat format) noexcept;

enum class PointType : std::uint32_t {
  unknown = 0,
  xyz32 = 1,          // 3 × float: x y z (the SIM paper's PointXYZ without padding), 12 B
  xyzi32 = 2,         // 4 × float: x y z intensity, 16 B
  lidar_point = 3,    // sim::LidarPoint (lidar_point.hpp), 24 B
};

const char* to_string(PointType type) noexcept;
std::uint32_t point_size(PointType type) noexcept;

struct ImageLayout {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint32_t channels = 0;
  std::uint32_t stride = 0;     // bytes per row; 0 for compressed formats
  PixelFormat format = PixelFormat::unknown;
  std::uint32_t bit_depth = 8;  // bits per channel

  // Bytes of one full frame (stride × height), or 0 for compressed formats.
  std::uint64_t frame_bytes() const noexcept { return std::uint64_t{stride} * height; }
  static ImageLayout packed(std::uint32_t width, std::uint32_t height, PixelFormat format) noexcept;
  // Every member, in order (written out rather than defaulted so C++17 consumers compile it).
  friend bool operator==(const ImageLayout& a, const ImageLayout& b) noexcept {
    return a.width == b.width && a.height == b.height && a.channels == b.channels &&
           a.stride == b.stride && a.format == b.format && a.bit_depth == b.bit_depth;
  }
  friend bool operator!=(const ImageLayout& a, const ImageLayout& b) noexcept { return !(a == b); }
};
static_assert(sizeof(ImageLayout) == 24, "a new member must be compared in operator==");

struct PointLayout {
  PointType type = PointType::unknown;
  std::uint32_t point_size = 0;  // bytes per point
  std::uint64_t max_points = 0;

  std::uint64_t frame_bytes() const noexcept { return std::uint64_t{point_size} * max_points; }
  static PointLayout of(PointType type, std::uint64_t max_points) noexcept;
  friend bool operator==(const PointLayout& a, const PointLayout& b) noexcept {
    return a.type == b.type && a.point_size == b.point_size && a.max_points == b.max_points;
  }
  friend bool operator!=(const PointLayout& a, const PointLayout& b) noexcept { return !(a == b); }
};
static_assert(sizeof(PointLayout) == 16, "a new member must be compared in operator==");

enum class LayoutKind : std::uint32_t { bytes = 0, image = 1, points = 2 };

struct Layout {
  LayoutKind kind = LayoutKind::bytes;
  ImageLayout image{};  // meaningful when kind == image
  PointLayout points{};  // meaningful when kind == points

  static Layout raw() noexcept { return {}; }
  static Layout of(const ImageLayout& image) noexcept { return {LayoutKind::image, image, {}}; }
  static Layout of(const PointLayout& points) noexcept { return {LayoutKind::points, {}, points}; }

  // Smallest slot capacity that holds every frame this layout can describe (0 for raw bytes and
  // compressed images, whose capacity the caller must choose).
  std::uint64_t min_capacity() const noexcept;
  // Empty when the layout is self-consistent and fits `capacity`; otherwise why not.
  std::string check(std::uint64_t capacity) const;
  // "image 640x480 bgr8 stride 1920", "points lidar_point x 115200", "bytes".
  std::string describe() const;
  friend bool operator==(const Layout& a, const Layout& b) noexcept {
    return a.kind == b.kind && a.image == b.image && a.points == b.points;
  }
  friend bool operator!=(const Layout& a, const Layout& b) noexcept { return !(a == b); }
};

}  // namespace sim
