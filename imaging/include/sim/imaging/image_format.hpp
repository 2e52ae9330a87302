// SPDX-License-Identifier: Apache-2.0
// The image formats a camera driver can publish, and the layouts they produce, shared by the
// V4L2 driver, the Aravis driver and the video replay so one consumer code path fits all three.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "sim/layout.hpp"

namespace sim::imaging {

// What the driver writes into the stream. `raw` publishes the device bytes unchanged (YUYV,
// MJPEG, Bayer, …) with their format recorded in the layout.
enum class OutputFormat : std::uint8_t { bgr8, rgb8, mono8, raw };

const char* to_string(OutputFormat output) noexcept;
std::optional<OutputFormat> parse_output_format(std::string_view text) noexcept;

// Compressed formats carry a different number of bytes in every frame and have no stride.
bool is_compressed(PixelFormat format) noexcept;

// Bytes in one row of pixels without padding (0 for compressed formats).
std::uint64_t row_bytes(std::uint32_t width, PixelFormat format) noexcept;

// A full image layout: channels, bit depth and stride filled in. `stride` 0 means rows are
// packed tightly; a larger stride keeps a device's row padding.
ImageLayout make_layout(std::uint32_t width, std::uint32_t height, PixelFormat format,
                        std::uint32_t stride = 0) noexcept;

// Smallest input a packed frame of this layout can arrive in: the last row needs no padding.
std::uint64_t min_input_bytes(const ImageLayout& layout) noexcept;

// The pixel format an output choice gives for a given input.
PixelFormat output_pixel_format(OutputFormat output, PixelFormat input) noexcept;

}  // namespace sim::imaging
