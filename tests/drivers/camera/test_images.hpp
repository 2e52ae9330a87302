// SPDX-License-Identifier: Apache-2.0
// Generated test images and OpenCV's reference conversions, kept in one translation unit so the
// test suites that only need bytes do not compile OpenCV's headers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/imaging/image_format.hpp"
#include "sim/layout.hpp"

namespace sim::camera::testing {

using Bytes = std::vector<std::byte>;

// A BGR scene (gradients, blocks, a seed-dependent disc) that JPEG and 4:2:2 treat like a photo.
Bytes scene_bgr(std::uint32_t width, std::uint32_t height, std::uint32_t seed);
// Pseudo-random bytes: valid YUYV, UYVY, grey, Y16 or Bayer data of any content.
Bytes noise(std::size_t size, std::uint32_t seed);
// The scene as a JPEG, 4:2:2 like UVC cameras send (or 4:2:0).
Bytes encode_jpeg(std::span<const std::byte> bgr, std::uint32_t width, std::uint32_t height,
                  int quality = 85, bool subsample_422 = true);
// OpenCV's own conversion of `input` (laid out as `layout`) to `output`, tightly packed:
// cv::cvtColor for packed formats, cv::imdecode for MJPEG. Empty if OpenCV cannot.
Bytes reference(const ImageLayout& layout, std::span<const std::byte> input, imaging::OutputFormat output);
// Largest absolute difference of two byte images of the same size (255 if sizes differ).
int max_difference(std::span<const std::byte> a, std::span<const std::byte> b);

}  // namespace sim::camera::testing
