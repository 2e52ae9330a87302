// SPDX-License-Identifier: Apache-2.0
// JPEG for --compress (libturbojpeg): encoding a SIM image frame into the bridge's own buffer,
// and reading the size of a received JPEG so it can become an mjpeg SIM stream.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::bridge {

// Pixel formats --compress can encode: mono8, bgr8, rgb8, bgra8, rgba8.
bool jpeg_can_encode(PixelFormat format) noexcept;

class JpegEncoder {
 public:
  explicit JpegEncoder(int quality);
  JpegEncoder(JpegEncoder&&) noexcept;
  JpegEncoder& operator=(JpegEncoder&&) noexcept;
  ~JpegEncoder();

  // The JPEG of one frame, in a buffer reused by the next call.
  Expected<std::span<const std::byte>> encode(const ImageLayout& layout,
                                              std::span<const std::byte> pixels);

 private:
  void* handle_ = nullptr;
  int quality_;
  std::vector<std::byte> buffer_;
};

struct JpegSize {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};
// The dimensions in a JPEG's header; an error when the bytes do not start a JPEG.
Expected<JpegSize> jpeg_size(std::span<const std::byte> jpeg);

}  // namespace sim::bridge
