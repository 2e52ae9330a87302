// SPDX-License-Identifier: Apache-2.0
#include "jpeg.hpp"

#include <turbojpeg.h>

#include <string>
#include <utility>

namespace sim::bridge {

namespace {
int tj_pixel_format(PixelFormat format) {
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

bool jpeg_can_encode(PixelFormat format) noexcept { return tj_pixel_format(format) >= 0; }

JpegEncoder::JpegEncoder(int quality) : handle_(tjInitCompress()), quality_(quality) {}
JpegEncoder::JpegEncoder(JpegEncoder&& other) noexcept
    : handle_(std::exchange(other.handle_, nullptr)),
      quality_(other.quality_),
      buffer_(std::move(other.buffer_)) {}
JpegEncoder& JpegEncoder::operator=(JpegEncoder&& other) noexcept {
  std::swap(handle_, other.handle_);
  quality_ = other.quality_;
  buffer_ = std::move(other.buffer_);
  return *this;
}
JpegEncoder::~JpegEncoder() {
  if (handle_ != nullptr) tjDestroy(handle_);
}

Expected<std::span<const std::byte>> JpegEncoder::encode(const ImageLayout& layout,
                                                         std::span<const std::byte> pixels) {
  const int format = tj_pixel_format(layout.format);
  if (handle_ == nullptr || format < 0) {
    return Error{ErrorCode::invalid_argument,
                 std::string("--compress jpeg cannot encode ") + to_string(layout.format) +
                     " images; it encodes mono8, bgr8, rgb8, bgra8 and rgba8"};
  }
  if (pixels.size() < layout.frame_bytes()) {
    return Error{ErrorCode::invalid_argument, "the image frame is shorter than its layout"};
  }
  const int subsampling = layout.format == PixelFormat::mono8 ? TJSAMP_GRAY : TJSAMP_420;
  const auto width = static_cast<int>(layout.width);
  const auto height = static_cast<int>(layout.height);
  // The worst case, so turbojpeg never reallocates our buffer.
  buffer_.resize(tjBufSize(width, height, subsampling));
  auto* out = reinterpret_cast<unsigned char*>(buffer_.data());
  unsigned long size = buffer_.size();
  if (tjCompress2(handle_, reinterpret_cast<const unsigned char*>(pixels.data()), width,
                  static_cast<int>(layout.stride), height, format, &out, &size, subsampling,
                  quality_, TJFLAG_NOREALLOC | TJFLAG_FASTDCT) != 0) {
    return Error{ErrorCode::system_error, std::string("JPEG encoding failed: ") + tjGetErrorStr2(handle_)};
  }
  return std::span<const std::byte>(buffer_.data(), size);
}

Expected<JpegSize> jpeg_size(std::span<const std::byte> jpeg) {
  tjhandle handle = tjInitDecompress();
  if (handle == nullptr) return Error{ErrorCode::system_error, "libturbojpeg could not start"};
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  const int rc = tjDecompressHeader3(handle, reinterpret_cast<const unsigned char*>(jpeg.data()),
                                     static_cast<unsigned long>(jpeg.size()), &width, &height,
                                     &subsampling, &colorspace);
  tjDestroy(handle);
  if (rc != 0 || width <= 0 || height <= 0) {
    return Error{ErrorCode::invalid_argument,
                 "the CompressedImage data is not a JPEG with a readable header"};
  }
  return JpegSize{static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
}

}  // namespace sim::bridge
