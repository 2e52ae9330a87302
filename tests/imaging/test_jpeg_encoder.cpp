// SPDX-License-Identifier: Apache-2.0
// JPEG encoding: what it makes decodes back (through the drivers' own decoder) to nearly the
// same image, and what it cannot encode gets one sentence.
#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "sim/imaging/decoder.hpp"
#include "sim/imaging/image_format.hpp"
#include "sim/imaging/jpeg_encoder.hpp"

namespace {

using namespace sim;
using namespace sim::imaging;

// Smooth gradients with a padded stride: what JPEG keeps well.
std::vector<std::byte> gradient(const ImageLayout& layout) {
  std::vector<std::byte> pixels(layout.frame_bytes());
  for (std::uint32_t y = 0; y < layout.height; ++y) {
    for (std::uint32_t x = 0; x < layout.width; ++x) {
      for (std::uint32_t c = 0; c < layout.channels; ++c) {
        pixels[y * layout.stride + x * layout.channels + c] =
            static_cast<std::byte>((x * 2 + y + c * 40) & 0xFF);
      }
    }
  }
  return pixels;
}

TEST(JpegEncoder, AnImageDecodesBackToNearlyTheSamePixels) {
  const ImageLayout layout = make_layout(64, 48, PixelFormat::bgr8, 64 * 3 + 16);
  const auto pixels = gradient(layout);
  auto encoder = JpegEncoder::create(95);
  ASSERT_TRUE(encoder);
  std::vector<std::byte> jpeg;
  ASSERT_FALSE(encoder->encode(layout, pixels, jpeg).has_value());
  ASSERT_GT(jpeg.size(), 2U);
  EXPECT_EQ(jpeg[0], std::byte{0xFF});
  EXPECT_EQ(jpeg[1], std::byte{0xD8});  // SOI marker

  auto decoder = FrameDecoder::create(make_layout(64, 48, PixelFormat::mjpeg), OutputFormat::bgr8);
  ASSERT_TRUE(decoder);
  std::vector<std::byte> decoded(decoder->output_layout().frame_bytes());
  const DecodeResult result = decoder->decode(jpeg, decoded);
  ASSERT_EQ(result.status, DecodeStatus::ok);
  int worst = 0;
  for (std::uint32_t y = 0; y < 48; ++y) {
    for (std::uint32_t x = 0; x < 64 * 3; ++x) {
      const int a = static_cast<int>(pixels[y * layout.stride + x]);
      const int b = static_cast<int>(decoded[y * 64 * 3 + x]);
      worst = std::max(worst, std::abs(a - b));
    }
  }
  EXPECT_LE(worst, 24);
}

TEST(JpegEncoder, AGreyImageEncodes) {
  const ImageLayout layout = make_layout(32, 32, PixelFormat::mono8);
  const auto pixels = gradient(layout);
  auto encoder = JpegEncoder::create();
  ASSERT_TRUE(encoder);
  std::vector<std::byte> jpeg;
  EXPECT_FALSE(encoder->encode(layout, pixels, jpeg).has_value());
  EXPECT_GT(jpeg.size(), 100U);
}

TEST(JpegEncoder, AShortImageOrAnotherFormatGetsOneSentence) {
  auto encoder = JpegEncoder::create();
  ASSERT_TRUE(encoder);
  std::vector<std::byte> jpeg;
  const ImageLayout layout = make_layout(64, 48, PixelFormat::bgr8);
  std::vector<std::byte> short_image(100);
  const auto short_error = encoder->encode(layout, short_image, jpeg);
  ASSERT_TRUE(short_error.has_value());
  EXPECT_NE(short_error->message.find("fewer than"), std::string::npos);
  const ImageLayout yuyv = make_layout(64, 48, PixelFormat::yuyv);
  std::vector<std::byte> frame(yuyv.frame_bytes());
  EXPECT_TRUE(encoder->encode(yuyv, frame, jpeg).has_value());
  EXPECT_FALSE(JpegEncoder::create(0));
}

}  // namespace
