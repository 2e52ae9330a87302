// SPDX-License-Identifier: Apache-2.0
#include "jpeg.hpp"

#include <turbojpeg.h>

#include <string>
#include <utility>

namespace sim::foxglove {
namespace {

// libjpeg-turbo's pixel format for a SIM format it can compress directly; -1 if none.
int direct_pixel_format(PixelFormat format) {
  switch (format) {
    case PixelFormat::mono8: return TJPF_GRAY;
    case PixelFormat::bgr8: return TJPF_BGR;
    case PixelFormat::rgb8: return TJPF_RGB;
    case PixelFormat::bgra8: return TJPF_BGRA;
    case PixelFormat::rgba8: return TJPF_RGBA;
    default: return -1;
  }
}

}  // namespace

JpegEncoder::JpegEncoder(void* handle) noexcept : handle_(handle) {}
JpegEncoder::JpegEncoder(JpegEncoder&& other) noexcept
    : handle_(std::exchange(other.handle_, nullptr)),
      decoder_(std::move(other.decoder_)),
      decoder_layout_(other.decoder_layout_),
      converted_(std::move(other.converted_)) {}
JpegEncoder& JpegEncoder::operator=(JpegEncoder&& other) noexcept {
  if (this != &other) {
    if (handle_ != nullptr) tjDestroy(handle_);
    handle_ = std::exchange(other.handle_, nullptr);
    decoder_ = std::move(other.decoder_);
    decoder_layout_ = other.decoder_layout_;
    converted_ = std::move(other.converted_);
  }
  return *this;
}
JpegEncoder::~JpegEncoder() {
  if (handle_ != nullptr) tjDestroy(handle_);
}

Expected<JpegEncoder> JpegEncoder::create() {
  tjhandle handle = tjInitCompress();
  if (handle == nullptr) {
    return Error{ErrorCode::system_error,
                 "libjpeg-turbo could not start a compressor; check that libturbojpeg is installed."};
  }
  return JpegEncoder(handle);
}

std::optional<Error> JpegEncoder::compress(const unsigned char* pixels, std::uint32_t width,
                                           std::uint32_t height, std::uint32_t pitch,
                                           int pixel_format, int quality,
                                           std::vector<std::byte>& out) {
  const int subsampling = pixel_format == TJPF_GRAY ? TJSAMP_GRAY : TJSAMP_420;
  const unsigned long bound =
      tjBufSize(static_cast<int>(width), static_cast<int>(height), subsampling);
  if (bound == static_cast<unsigned long>(-1)) {
    return Error{ErrorCode::invalid_argument, "the image is too large to compress as JPEG."};
  }
  out.resize(bound);
  auto* dest = reinterpret_cast<unsigned char*>(out.data());
  unsigned long size = bound;
  // NOREALLOC: libjpeg-turbo writes into our buffer, sized by tjBufSize for the worst case.
  if (tjCompress2(handle_, pixels, static_cast<int>(width), static_cast<int>(pitch),
                  static_cast<int>(height), pixel_format, &dest, &size, subsampling, quality,
                  TJFLAG_NOREALLOC | TJFLAG_FASTDCT) != 0) {
    return Error{ErrorCode::system_error,
                 std::string("libjpeg-turbo refused the image: ") + tjGetErrorStr2(handle_) + "."};
  }
  out.resize(size);
  return std::nullopt;
}

std::optional<Error> JpegEncoder::encode(const ImageLayout& layout,
                                         std::span<const std::byte> frame, int quality,
                                         std::vector<std::byte>& out) {
  if (layout.format == PixelFormat::mjpeg) {
    out.assign(frame.begin(), frame.end());
    return std::nullopt;
  }
  if (layout.width == 0 || layout.height == 0 || layout.width > 65535 || layout.height > 65535) {
    return Error{ErrorCode::invalid_argument, "the stream's image size " +
                                                  std::to_string(layout.width) + "x" +
                                                  std::to_string(layout.height) +
                                                  " cannot be compressed; restart its writer."};
  }
  if (const int pf = direct_pixel_format(layout.format); pf >= 0) {
    const std::uint64_t needed =
        std::uint64_t{layout.stride} * (layout.height - 1) +
        std::uint64_t{layout.width} * static_cast<std::uint64_t>(tjPixelSize[pf]);
    if (layout.stride < layout.width * static_cast<std::uint32_t>(tjPixelSize[pf]) ||
        frame.size() < needed) {
      return Error{ErrorCode::invalid_argument,
                   "the frame holds " + std::to_string(frame.size()) + " bytes, too few for " +
                       Layout::of(layout).describe() + "; nothing was sent."};
    }
    return compress(reinterpret_cast<const unsigned char*>(frame.data()), layout.width,
                    layout.height, layout.stride, pf, quality, out);
  }
  if (!decoder_ || !(decoder_layout_ == layout)) {
    auto decoder = camera::FrameDecoder::create(layout, camera::OutputFormat::bgr8);
    if (!decoder) {
      decoder_.reset();
      return Error{ErrorCode::invalid_argument,
                   "cannot show " + Layout::of(layout).describe() + " as JPEG: " +
                       decoder.error().message};
    }
    decoder_.emplace(std::move(decoder.value()));
    decoder_layout_ = layout;
    converted_.resize(decoder_->output_layout().frame_bytes());
  }
  const camera::DecodeResult decoded = decoder_->decode(frame, converted_);
  if (decoded.status != camera::DecodeStatus::ok) {
    return Error{ErrorCode::invalid_argument,
                 std::string("the frame does not convert to BGR (") +
                     camera::to_string(decoded.status) + "); nothing was sent."};
  }
  const ImageLayout& bgr = decoder_->output_layout();
  return compress(reinterpret_cast<const unsigned char*>(converted_.data()), bgr.width,
                  bgr.height, bgr.stride, TJPF_BGR, quality, out);
}

std::optional<Error> JpegEncoder::encode_rgb(std::uint32_t width, std::uint32_t height,
                                             std::span<const std::uint8_t> rgb, int quality,
                                             std::vector<std::byte>& out) {
  if (rgb.size() < std::uint64_t{width} * height * 3) {
    return Error{ErrorCode::invalid_argument, "the RGB raster is smaller than its size says."};
  }
  return compress(rgb.data(), width, height, width * 3, TJPF_RGB, quality, out);
}

}  // namespace sim::foxglove
