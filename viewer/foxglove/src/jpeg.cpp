// SPDX-License-Identifier: Apache-2.0
#include "jpeg.hpp"

#include <cstring>
#include <string>
#include <utility>

namespace sim::foxglove {
namespace {

bool encodes_directly(PixelFormat format) {
  return format == PixelFormat::bgr8 || format == PixelFormat::rgb8 ||
         format == PixelFormat::mono8;
}

}  // namespace

Expected<ImageToJpeg> ImageToJpeg::create(int quality) {
  auto jpeg = imaging::JpegEncoder::create(quality);
  if (!jpeg) return jpeg.error();
  return ImageToJpeg(std::move(jpeg.value()));
}

std::optional<Error> ImageToJpeg::encode(const ImageLayout& layout,
                                         std::span<const std::byte> frame,
                                         std::vector<std::byte>& out) {
  if (layout.format == PixelFormat::mjpeg) {
    // A broken camera frame would show as the browser's broken-image icon: say what is wrong.
    if (auto size = imaging::read_jpeg_size(frame); !size) {
      return Error{ErrorCode::invalid_argument,
                   "the camera's newest MJPEG frame cannot be shown: " + size.error().message +
                       "; the next frame may be whole."};
    }
    out.assign(frame.begin(), frame.end());
    return std::nullopt;
  }
  if (encodes_directly(layout.format)) return jpeg_.encode(layout, frame, out);
  if (auto error = convert(layout, frame)) return error;
  return jpeg_.encode(decoder_->output_layout(), converted_, out);
}

std::optional<Error> ImageToJpeg::convert(const ImageLayout& layout,
                                          std::span<const std::byte> frame) {
  if (!decoder_ || !(decoder_layout_ == layout)) {
    auto decoder = imaging::FrameDecoder::create(layout, imaging::OutputFormat::bgr8);
    if (!decoder) {
      decoder_.reset();
      return Error{ErrorCode::invalid_argument, "cannot show " + Layout::of(layout).describe() +
                                                    " as JPEG: " + decoder.error().message};
    }
    decoder_.emplace(std::move(decoder.value()));
    decoder_layout_ = layout;
    converted_.resize(decoder_->output_layout().frame_bytes());
  }
  const imaging::DecodeResult decoded = decoder_->decode(frame, converted_);
  if (decoded.status != imaging::DecodeStatus::ok) {
    return Error{ErrorCode::invalid_argument, std::string("the frame does not convert to BGR (") +
                                                  imaging::to_string(decoded.status) +
                                                  "); nothing was sent."};
  }
  return std::nullopt;
}

std::optional<Error> ImageToJpeg::to_bgr(const ImageLayout& layout,
                                         std::span<const std::byte> frame,
                                         std::vector<std::uint8_t>& bgr) {
  const std::size_t row = std::size_t{layout.width} * 3;
  bgr.resize(row * layout.height);
  if (layout.format == PixelFormat::bgr8) {
    if (frame.size() < layout.frame_bytes() || layout.stride < row) {
      return Error{ErrorCode::invalid_argument, "the frame is shorter than its layout says."};
    }
    for (std::uint32_t y = 0; y < layout.height; ++y) {
      std::memcpy(bgr.data() + y * row, frame.data() + std::size_t{y} * layout.stride, row);
    }
    return std::nullopt;
  }
  if (auto error = convert(layout, frame)) return error;
  const ImageLayout& out = decoder_->output_layout();
  for (std::uint32_t y = 0; y < layout.height; ++y) {
    std::memcpy(bgr.data() + y * row, converted_.data() + std::size_t{y} * out.stride, row);
  }
  return std::nullopt;
}

std::optional<Error> ImageToJpeg::encode_bgr(std::uint32_t width, std::uint32_t height,
                                             std::span<const std::uint8_t> bgr,
                                             std::vector<std::byte>& out) {
  return jpeg_.encode(ImageLayout::packed(width, height, PixelFormat::bgr8), std::as_bytes(bgr),
                      out);
}

std::optional<Error> ImageToJpeg::encode_rgb(std::uint32_t width, std::uint32_t height,
                                             std::span<const std::uint8_t> rgb,
                                             std::vector<std::byte>& out) {
  return jpeg_.encode(ImageLayout::packed(width, height, PixelFormat::rgb8), std::as_bytes(rgb),
                      out);
}

}  // namespace sim::foxglove
