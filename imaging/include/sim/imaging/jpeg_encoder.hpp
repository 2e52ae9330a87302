// SPDX-License-Identifier: Apache-2.0
// JPEG encoding of a published image (bgr8, rgb8, mono8), for consumers that send images on
// (a CompressedImage, a viewer, a file). Decoding is FrameDecoder's job (MJPEG input).
#pragma once

#include <cstddef>
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

  // Encodes one image of `layout` (bgr8, rgb8 or mono8, any stride) into `out`, which is resized
  // to the JPEG's size and reused between calls. One sentence for another format or a short
  // input.
  std::optional<Error> encode(const ImageLayout& layout, std::span<const std::byte> pixels,
                              std::vector<std::byte>& out);

 private:
  struct Impl;
  explicit JpegEncoder(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::imaging
