// SPDX-License-Identifier: Apache-2.0
// JPEG encoding of a published image (bgr8, rgb8, bgra8, rgba8, mono8), for consumers that send
// images on (a CompressedImage, a viewer, a file). Decoding is FrameDecoder's job (MJPEG input).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::imaging {

class JpegEncoder {
 public:
  // quality 1..100 (libjpeg's scale); one sentence when it is out of range.
  static Expected<JpegEncoder> create(int quality = 90);

  JpegEncoder(JpegEncoder&&) noexcept;
  JpegEncoder& operator=(JpegEncoder&&) noexcept;
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;
  ~JpegEncoder();

  // Whether encode() takes images of this format: bgr8, rgb8, bgra8 and rgba8 (4:2:0 colour,
  // alpha left out) and mono8 (greyscale).
  static bool encodes(PixelFormat format) noexcept;

  // Encodes one image of `layout` (a format encodes() takes, any stride) into the encoder's own
  // buffer: the JPEG's bytes, valid until the next call, for a caller that sends them on at once
  // (a DDS payload: no copy in between). One sentence for another format or a short input.
  Expected<std::span<const std::byte>> encode(const ImageLayout& layout,
                                              std::span<const std::byte> pixels);
  // The same, copied into `out`, which is resized to the JPEG's size and reused between calls.
  std::optional<Error> encode(const ImageLayout& layout, std::span<const std::byte> pixels,
                              std::vector<std::byte>& out);

 private:
  struct Impl;
  explicit JpegEncoder(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// The width and height a JPEG's header announces, read without decoding the image: for
// consumers that size a stream for JPEGs they receive.
struct JpegSize {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};
// One sentence when the bytes do not start a JPEG with a readable header, or hold a header but
// no scan data (nothing a decoder could turn into pixels).
Expected<JpegSize> read_jpeg_size(std::span<const std::byte> jpeg);

}  // namespace sim::imaging
