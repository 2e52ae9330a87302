// SPDX-License-Identifier: Apache-2.0
#include "jpeg.hpp"

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
    out.assign(frame.begin(), frame.end());
    return std::nullopt;
  }
  if (encodes_directly(layout.format)) return jpeg_.encode(layout, frame, out);
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
  return jpeg_.encode(decoder_->output_layout(), converted_, out);
}

std::optional<Error> ImageToJpeg::encode_rgb(std::uint32_t width, std::uint32_t height,
                                             std::span<const std::uint8_t> rgb,
                                             std::vector<std::byte>& out) {
  return jpeg_.encode(ImageLayout::packed(width, height, PixelFormat::rgb8), std::as_bytes(rgb),
                      out);
}

}  // namespace sim::foxglove
