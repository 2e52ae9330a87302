// SPDX-License-Identifier: Apache-2.0
// JPEG for image streams of any SIM pixel format (libjpeg-turbo): formats libjpeg-turbo takes
// as they are (mono8, BGR/RGB and their alpha variants) are compressed straight from the frame;
// the others (Bayer, packed YUV, mono16) go through the camera drivers' own decoder to BGR first,
// so the picture matches what sim_dump and the drivers make of the frame. One per thread.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "sim/camera/decoder.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::foxglove {

class JpegEncoder {
 public:
  static Expected<JpegEncoder> create();
  JpegEncoder(JpegEncoder&&) noexcept;
  JpegEncoder& operator=(JpegEncoder&&) noexcept;
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;
  ~JpegEncoder();

  // Compresses one frame of `layout` at `quality` (1–100) into `out`. An MJPEG frame is copied
  // as it is. The error is one sentence (a format nothing here converts, a short frame).
  std::optional<Error> encode(const ImageLayout& layout, std::span<const std::byte> frame,
                              int quality, std::vector<std::byte>& out);
  // Compresses tightly packed 8-bit RGB pixels (the top-down view).
  std::optional<Error> encode_rgb(std::uint32_t width, std::uint32_t height,
                                  std::span<const std::uint8_t> rgb, int quality,
                                  std::vector<std::byte>& out);

 private:
  explicit JpegEncoder(void* handle) noexcept;
  std::optional<Error> compress(const unsigned char* pixels, std::uint32_t width,
                                std::uint32_t height, std::uint32_t pitch, int pixel_format,
                                int quality, std::vector<std::byte>& out);
  void* handle_ = nullptr;  // tjhandle
  // Conversion to BGR for formats libjpeg-turbo cannot take, kept while the layout stays.
  std::optional<camera::FrameDecoder> decoder_;
  ImageLayout decoder_layout_{};
  std::vector<std::byte> converted_;
};

}  // namespace sim::foxglove
