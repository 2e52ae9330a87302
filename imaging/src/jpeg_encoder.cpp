// SPDX-License-Identifier: Apache-2.0
#include "sim/imaging/jpeg_encoder.hpp"

#include <turbojpeg.h>

#include <optional>
#include <string>

#include "sim/imaging/image_format.hpp"

namespace sim::imaging {

struct JpegEncoder::Impl {
  tjhandle handle = nullptr;
  int quality = 90;
  ~Impl() {
    if (handle != nullptr) tjDestroy(handle);
  }
};

JpegEncoder::JpegEncoder(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
JpegEncoder::JpegEncoder(JpegEncoder&&) noexcept = default;
JpegEncoder& JpegEncoder::operator=(JpegEncoder&&) noexcept = default;
JpegEncoder::~JpegEncoder() = default;

Expected<JpegEncoder> JpegEncoder::create(int quality) {
  if (quality < 1 || quality > 100) {
    return Error{ErrorCode::invalid_argument,
                 "JPEG quality " + std::to_string(quality) + " is outside 1..100; choose 90"};
  }
  auto impl = std::make_unique<Impl>();
  impl->handle = tjInitCompress();
  if (impl->handle == nullptr) {
    return Error{ErrorCode::system_error, "libjpeg-turbo could not start a JPEG encoder"};
  }
  impl->quality = quality;
  return JpegEncoder(std::move(impl));
}

std::optional<Error> JpegEncoder::encode(const ImageLayout& layout,
                                         std::span<const std::byte> pixels,
                                         std::vector<std::byte>& out) {
  int format = -1;
  int subsampling = TJSAMP_420;
  switch (layout.format) {
    case PixelFormat::bgr8: format = TJPF_BGR; break;
    case PixelFormat::rgb8: format = TJPF_RGB; break;
    case PixelFormat::mono8:
      format = TJPF_GRAY;
      subsampling = TJSAMP_GRAY;
      break;
    default:
      return Error{ErrorCode::invalid_argument,
                   "JPEG encoding takes bgr8, rgb8 or mono8 images; convert the image first"};
  }
  if (layout.width == 0 || layout.height == 0 || pixels.size() < min_input_bytes(layout)) {
    return Error{ErrorCode::invalid_argument,
                 "the image holds " + std::to_string(pixels.size()) + " bytes, fewer than its " +
                     std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                     " layout needs"};
  }
  const unsigned long bound = tjBufSize(static_cast<int>(layout.width),
                                        static_cast<int>(layout.height), subsampling);
  out.resize(bound);
  auto* destination = reinterpret_cast<unsigned char*>(out.data());
  unsigned long size = bound;
  const int rc = tjCompress2(impl_->handle, reinterpret_cast<const unsigned char*>(pixels.data()),
                             static_cast<int>(layout.width), static_cast<int>(layout.stride),
                             static_cast<int>(layout.height), format, &destination, &size,
                             subsampling, impl_->quality, TJFLAG_NOREALLOC);
  if (rc != 0) {
    return Error{ErrorCode::system_error,
                 std::string("libjpeg-turbo could not encode the image: ") +
                     tjGetErrorStr2(impl_->handle)};
  }
  out.resize(size);
  return std::nullopt;
}

}  // namespace sim::imaging
