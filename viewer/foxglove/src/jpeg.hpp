// SPDX-License-Identifier: Apache-2.0
// Any SIM image as JPEG, for the page and for --compress jpeg. The JPEG coding and the pixel
// conversions are the project's own (sim::imaging): bgr8, rgb8 and mono8 are encoded straight
// from the frame; every other format (alpha, Bayer, packed YUV, …) goes through the camera
// drivers' FrameDecoder to BGR first, so the picture matches what the drivers and sim_dump make
// of the frame; MJPEG frames are already JPEG and are copied. One per thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/imaging/decoder.hpp"
#include "sim/imaging/jpeg_encoder.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::foxglove {

class ImageToJpeg {
 public:
  // quality 1–100.
  static Expected<ImageToJpeg> create(int quality);

  // Compresses one frame of `layout` into `out`. The error is one sentence (a format nothing
  // here converts, a short frame).
  std::optional<Error> encode(const ImageLayout& layout, std::span<const std::byte> frame,
                              std::vector<std::byte>& out);
  // The frame as tightly packed 8-bit BGR (to draw on); the error is one sentence.
  std::optional<Error> to_bgr(const ImageLayout& layout, std::span<const std::byte> frame,
                              std::vector<std::uint8_t>& bgr);
  // Compresses tightly packed 8-bit BGR pixels (a picture drawn on).
  std::optional<Error> encode_bgr(std::uint32_t width, std::uint32_t height,
                                  std::span<const std::uint8_t> bgr, std::vector<std::byte>& out);
  // Compresses tightly packed 8-bit RGB pixels (the top-down view).
  std::optional<Error> encode_rgb(std::uint32_t width, std::uint32_t height,
                                  std::span<const std::uint8_t> rgb, std::vector<std::byte>& out);

 private:
  explicit ImageToJpeg(imaging::JpegEncoder jpeg) : jpeg_(std::move(jpeg)) {}
  // Converts a frame of a format the encoder does not take to BGR (in converted_).
  std::optional<Error> convert(const ImageLayout& layout, std::span<const std::byte> frame);
  imaging::JpegEncoder jpeg_;
  // Conversion to BGR for formats the encoder does not take, kept while the layout stays.
  std::optional<imaging::FrameDecoder> decoder_;
  ImageLayout decoder_layout_{};
  std::vector<std::byte> converted_;
};

}  // namespace sim::foxglove
