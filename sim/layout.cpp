// SPDX-License-Identifier: Apache-2.0
#include "sim/layout.hpp"

#include "sim/reader.hpp"
#include "sim/result.hpp"
#include "sim/writer.hpp"

namespace sim {

const char* to_string(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::unknown: return "unknown";
    case PixelFormat::mono8: return "mono8";
    case PixelFormat::mono16: return "mono16";
    case PixelFormat::bgr8: return "bgr8";
    case PixelFormat::rgb8: return "rgb8";
    case PixelFormat::bgra8: return "bgra8";
    case PixelFormat::rgba8: return "rgba8";
    case PixelFormat::yuyv: return "yuyv";
    case PixelFormat::uyvy: return "uyvy";
    case PixelFormat::bayer_rggb8: return "bayer_rggb8";
    case PixelFormat::bayer_bggr8: return "bayer_bggr8";
    case PixelFormat::bayer_gbrg8: return "bayer_gbrg8";
    case PixelFormat::bayer_grbg8: return "bayer_grbg8";
    case PixelFormat::mjpeg: return "mjpeg";
  }
  return "invalid";
}

namespace {
struct FormatShape {
  std::uint32_t bytes_per_pixel;
  std::uint32_t channels;
  std::uint32_t bit_depth;
};
FormatShape shape_of(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::mono8: return {1, 1, 8};
    case PixelFormat::mono16: return {2, 1, 16};
    case PixelFormat::bgr8:
    case PixelFormat::rgb8: return {3, 3, 8};
    case PixelFormat::bgra8:
    case PixelFormat::rgba8: return {4, 4, 8};
    case PixelFormat::yuyv:
    case PixelFormat::uyvy: return {2, 2, 8};
    case PixelFormat::bayer_rggb8:
    case PixelFormat::bayer_bggr8:
    case PixelFormat::bayer_gbrg8:
    case PixelFormat::bayer_grbg8: return {1, 1, 8};
    case PixelFormat::mjpeg:
    case PixelFormat::unknown: return {0, 0, 8};
  }
  return {0, 0, 0};
}
bool known(PixelFormat format) noexcept {
  return static_cast<std::uint32_t>(format) <= static_cast<std::uint32_t>(PixelFormat::mjpeg);
}
}  // namespace

std::uint32_t bytes_per_pixel(PixelFormat format) noexcept { return shape_of(format).bytes_per_pixel; }

const char* to_string(PointType type) noexcept {
  switch (type) {
    case PointType::unknown: return "unknown";
    case PointType::xyz32: return "xyz32";
    case PointType::xyzi32: return "xyzi32";
    case PointType::lidar_point: return "lidar_point";
  }
  return "invalid";
}

std::uint32_t point_size(PointType type) noexcept {
  switch (type) {
    case PointType::xyz32: return 12;
    case PointType::xyzi32: return 16;
    case PointType::lidar_point: return 24;
    case PointType::unknown: return 0;
  }
  return 0;
}

ImageLayout ImageLayout::packed(std::uint32_t width, std::uint32_t height,
                                PixelFormat format) noexcept {
  const FormatShape s = shape_of(format);
  return {width, height, s.channels, width * s.bytes_per_pixel, format, s.bit_depth};
}

PointLayout PointLayout::of(PointType type, std::uint64_t max_points) noexcept {
  return {type, sim::point_size(type), max_points};
}

std::uint64_t Layout::min_capacity() const noexcept {
  switch (kind) {
    case LayoutKind::image: return image.frame_bytes();
    case LayoutKind::points: return points.frame_bytes();
    case LayoutKind::bytes: return 0;
  }
  return 0;
}

std::string Layout::check(std::uint64_t capacity) const {
  switch (kind) {
    case LayoutKind::bytes: return {};
    case LayoutKind::image: {
      if (!known(image.format) || image.format == PixelFormat::unknown) {
        return "the image pixel format is unknown";
      }
      if (image.width == 0 || image.height == 0 || image.width > 65536 || image.height > 65536) {
        return "the image size " + std::to_string(image.width) + "x" +
               std::to_string(image.height) + " is impossible";
      }
      const FormatShape s = shape_of(image.format);
      if (image.format == PixelFormat::mjpeg) return {};
      if (image.channels != s.channels || image.bit_depth != s.bit_depth) {
        return std::string("the channels or bit depth do not match pixel format ") +
               to_string(image.format);
      }
      if (image.stride < std::uint64_t{image.width} * s.bytes_per_pixel) {
        return "the image stride " + std::to_string(image.stride) + " is shorter than a row";
      }
      if (image.frame_bytes() > capacity) {
        return "an image of " + std::to_string(image.frame_bytes()) +
               " bytes does not fit the capacity of " + std::to_string(capacity) + " bytes";
      }
      return {};
    }
    case LayoutKind::points: {
      if (points.type == PointType::unknown || point_size(points.type) == 0) {
        return "the point type is unknown";
      }
      if (points.point_size != point_size(points.type)) {
        return std::string("the point size does not match point type ") + to_string(points.type);
      }
      if (points.max_points == 0 || points.max_points > capacity / points.point_size) {
        return "max_points " + std::to_string(points.max_points) +
               " does not fit the capacity of " + std::to_string(capacity) + " bytes";
      }
      return {};
    }
  }
  return "the layout kind is unknown";
}

std::string Layout::describe() const {
  switch (kind) {
    case LayoutKind::bytes: return "bytes";
    case LayoutKind::image:
      return "image " + std::to_string(image.width) + "x" + std::to_string(image.height) + " " +
             to_string(image.format) + " stride " + std::to_string(image.stride);
    case LayoutKind::points:
      return std::string("points ") + to_string(points.type) + " x " +
             std::to_string(points.max_points);
  }
  return "invalid";
}

const char* to_string(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::invalid_name: return "invalid_name";
    case ErrorCode::invalid_argument: return "invalid_argument";
    case ErrorCode::not_found: return "not_found";
    case ErrorCode::writer_exists: return "writer_exists";
    case ErrorCode::permission_denied: return "permission_denied";
    case ErrorCode::region_invalid: return "region_invalid";
    case ErrorCode::layout_mismatch: return "layout_mismatch";
    case ErrorCode::system_error: return "system_error";
  }
  return "invalid";
}

const char* to_string(WriteStatus status) noexcept {
  switch (status) {
    case WriteStatus::ok: return "ok";
    case WriteStatus::too_large: return "too_large";
    case WriteStatus::closed: return "closed";
    case WriteStatus::loan_open: return "loan_open";
  }
  return "invalid";
}

const char* to_string(ReadStatus status) noexcept {
  switch (status) {
    case ReadStatus::new_frame: return "new_frame";
    case ReadStatus::no_new_frame: return "no_new_frame";
    case ReadStatus::writer_gone: return "writer_gone";
    case ReadStatus::stale: return "stale";
    case ReadStatus::checksum_mismatch: return "checksum_mismatch";
    case ReadStatus::buffer_too_small: return "buffer_too_small";
    case ReadStatus::overrun: return "overrun";
    case ReadStatus::region_invalid: return "region_invalid";
  }
  return "invalid";
}

}  // namespace sim
