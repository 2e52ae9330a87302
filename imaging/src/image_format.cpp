// SPDX-License-Identifier: Apache-2.0
#include "sim/imaging/image_format.hpp"

namespace sim::imaging {

namespace {

struct PixelTraits {
  std::uint32_t channels;
  std::uint32_t bit_depth;
  std::uint32_t bytes_per_pixel;  // 0: compressed
};

PixelTraits traits(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::mono8:
    case PixelFormat::bayer_rggb8:
    case PixelFormat::bayer_bggr8:
    case PixelFormat::bayer_gbrg8:
    case PixelFormat::bayer_grbg8:
      return {1, 8, 1};
    case PixelFormat::mono16:
      return {1, 16, 2};
    case PixelFormat::bgr8:
    case PixelFormat::rgb8:
      return {3, 8, 3};
    case PixelFormat::bgra8:
    case PixelFormat::rgba8:
      return {4, 8, 4};
    case PixelFormat::yuyv:
    case PixelFormat::uyvy:
      return {2, 8, 2};  // two bytes per pixel: luma plus every other chroma sample
    case PixelFormat::mjpeg:
      return {0, 8, 0};  // channels unknown until decoded, as in sim::ImageLayout::packed
    case PixelFormat::unknown:
      break;
  }
  return {0, 8, 0};
}

}  // namespace

const char* to_string(OutputFormat output) noexcept {
  switch (output) {
    case OutputFormat::bgr8: return "bgr8";
    case OutputFormat::rgb8: return "rgb8";
    case OutputFormat::mono8: return "mono8";
    case OutputFormat::raw: return "raw";
  }
  return "?";
}

std::optional<OutputFormat> parse_output_format(std::string_view text) noexcept {
  for (auto output : {OutputFormat::bgr8, OutputFormat::rgb8, OutputFormat::mono8,
                      OutputFormat::raw}) {
    if (text == to_string(output)) return output;
  }
  return std::nullopt;
}

bool is_compressed(PixelFormat format) noexcept { return format == PixelFormat::mjpeg; }

std::uint64_t row_bytes(std::uint32_t width, PixelFormat format) noexcept {
  return std::uint64_t{width} * traits(format).bytes_per_pixel;
}

ImageLayout make_layout(std::uint32_t width, std::uint32_t height, PixelFormat format,
                        std::uint32_t stride) noexcept {
  const PixelTraits t = traits(format);
  ImageLayout layout;
  layout.width = width;
  layout.height = height;
  layout.channels = t.channels;
  layout.bit_depth = t.bit_depth;
  layout.format = format;
  const auto tight = static_cast<std::uint32_t>(row_bytes(width, format));
  layout.stride = is_compressed(format) ? 0 : (stride > tight ? stride : tight);
  return layout;
}

std::uint64_t min_input_bytes(const ImageLayout& layout) noexcept {
  if (is_compressed(layout.format) || layout.height == 0) return 0;
  return std::uint64_t{layout.stride} * (layout.height - 1) + row_bytes(layout.width, layout.format);
}

PixelFormat output_pixel_format(OutputFormat output, PixelFormat input) noexcept {
  switch (output) {
    case OutputFormat::bgr8: return PixelFormat::bgr8;
    case OutputFormat::rgb8: return PixelFormat::rgb8;
    case OutputFormat::mono8: return PixelFormat::mono8;
    case OutputFormat::raw: return input;
  }
  return PixelFormat::unknown;
}

}  // namespace sim::imaging
