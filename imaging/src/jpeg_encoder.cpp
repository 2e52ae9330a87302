// SPDX-License-Identifier: Apache-2.0
#include "sim/imaging/jpeg_encoder.hpp"

#include <turbojpeg.h>

#include <memory>
#include <optional>
#include <string>

#include "sim/imaging/image_format.hpp"

namespace sim::imaging {

struct JpegEncoder::Impl {
  tjhandle handle = nullptr;
  int quality = 90;
  // libjpeg-turbo's output: the worst case for the largest image so far, kept between calls and
  // never cleared (a vector resized to the worst case would zero megabytes per frame).
  std::unique_ptr<unsigned char[]> buffer;
  unsigned long buffer_size = 0;
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

namespace {

// libjpeg-turbo's name for the pixels of a SIM format, or -1 when it has none.
int turbojpeg_format(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::bgr8: return TJPF_BGR;
    case PixelFormat::rgb8: return TJPF_RGB;
    case PixelFormat::bgra8: return TJPF_BGRA;
    case PixelFormat::rgba8: return TJPF_RGBA;
    case PixelFormat::mono8: return TJPF_GRAY;
    default: return -1;
  }
}

}  // namespace

bool JpegEncoder::encodes(PixelFormat format) noexcept { return turbojpeg_format(format) >= 0; }

Expected<std::span<const std::byte>> JpegEncoder::encode(const ImageLayout& layout,
                                                         std::span<const std::byte> pixels) {
  const int format = turbojpeg_format(layout.format);
  if (format < 0) {
    return Error{ErrorCode::invalid_argument,
                 "JPEG encoding takes bgr8, rgb8, bgra8, rgba8 or mono8 images; convert the "
                 "image first"};
  }
  const int subsampling = layout.format == PixelFormat::mono8 ? TJSAMP_GRAY : TJSAMP_420;
  if (layout.width == 0 || layout.height == 0 || pixels.size() < min_input_bytes(layout)) {
    return Error{ErrorCode::invalid_argument,
                 "the image holds " + std::to_string(pixels.size()) + " bytes, fewer than its " +
                     std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                     " layout needs"};
  }
  const unsigned long bound = tjBufSize(static_cast<int>(layout.width),
                                        static_cast<int>(layout.height), subsampling);
  if (impl_->buffer_size < bound) {
    impl_->buffer.reset(new unsigned char[bound]);  // uninitialized: it is only written
    impl_->buffer_size = bound;
  }
  unsigned char* destination = impl_->buffer.get();
  unsigned long size = impl_->buffer_size;
  const int rc = tjCompress2(impl_->handle, reinterpret_cast<const unsigned char*>(pixels.data()),
                             static_cast<int>(layout.width), static_cast<int>(layout.stride),
                             static_cast<int>(layout.height), format, &destination, &size,
                             subsampling, impl_->quality, TJFLAG_NOREALLOC);
  if (rc != 0) {
    return Error{ErrorCode::system_error,
                 std::string("libjpeg-turbo could not encode the image: ") +
                     tjGetErrorStr2(impl_->handle)};
  }
  return std::span<const std::byte>(reinterpret_cast<const std::byte*>(destination), size);
}

std::optional<Error> JpegEncoder::encode(const ImageLayout& layout,
                                         std::span<const std::byte> pixels,
                                         std::vector<std::byte>& out) {
  auto jpeg = encode(layout, pixels);
  if (!jpeg) return jpeg.error();
  out.assign(jpeg->begin(), jpeg->end());
  return std::nullopt;
}

namespace {

// Whether a start of scan (SOS) is followed by entropy-coded data. A header alone passes
// libjpeg-turbo's header check but decodes to nothing, so it must not become a frame. Walks the
// marker segments after SOI; every length is checked against the end of the bytes.
bool has_scan_data(std::span<const std::byte> jpeg) noexcept {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned>(jpeg[i]); };
  std::size_t i = 2;  // after SOI, which the header check has seen
  while (i + 1 < jpeg.size()) {
    if (byte(i) != 0xFF) return false;
    const unsigned marker = byte(i + 1);
    if (marker == 0xFF) {  // a fill byte before the marker
      ++i;
      continue;
    }
    if (marker == 0xD9) return false;  // EOI before any scan
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {  // markers without a length
      i += 2;
      continue;
    }
    if (i + 3 >= jpeg.size()) return false;
    const std::size_t length = (byte(i + 2) << 8) | byte(i + 3);
    if (length < 2) return false;
    const std::size_t next = i + 2 + length;
    if (marker == 0xDA) {
      if (next >= jpeg.size()) return false;
      // At least one byte of scan data that is not the EOI marker itself.
      return !(jpeg.size() - next == 2 && byte(next) == 0xFF && byte(next + 1) == 0xD9);
    }
    i = next;
  }
  return false;
}

}  // namespace

Expected<JpegSize> read_jpeg_size(std::span<const std::byte> jpeg) {
  tjhandle handle = tjInitDecompress();
  if (handle == nullptr) {
    return Error{ErrorCode::system_error, "libjpeg-turbo could not start a JPEG decoder"};
  }
  int width = 0;
  int height = 0;
  int subsampling = 0;
  int colorspace = 0;
  const int rc = tjDecompressHeader3(handle, reinterpret_cast<const unsigned char*>(jpeg.data()),
                                     static_cast<unsigned long>(jpeg.size()), &width, &height,
                                     &subsampling, &colorspace);
  tjDestroy(handle);
  if (rc != 0 || width <= 0 || height <= 0) {
    return Error{ErrorCode::invalid_argument,
                 "the " + std::to_string(jpeg.size()) +
                     " bytes are not a JPEG with a readable header"};
  }
  if (!has_scan_data(jpeg)) {
    return Error{ErrorCode::invalid_argument,
                 "the " + std::to_string(jpeg.size()) +
                     "-byte JPEG has a header but no scan data (cut short, or only a header); "
                     "send whole JPEG frames"};
  }
  return JpegSize{static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
}

}  // namespace sim::imaging
