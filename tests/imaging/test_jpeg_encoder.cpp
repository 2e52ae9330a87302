// SPDX-License-Identifier: Apache-2.0
// JPEG encoding: what it makes decodes back (through the drivers' own decoder) to nearly the
// same image, and what it cannot encode gets one sentence; a JPEG's header gives its size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <span>
#include <string>
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
  // The same JPEG as a view of the encoder's own buffer (what a sender copies straight on).
  auto view = encoder->encode(layout, pixels);
  ASSERT_TRUE(view) << view.error().message;
  EXPECT_TRUE(std::equal(view->begin(), view->end(), jpeg.begin(), jpeg.end()));

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

TEST(JpegEncoder, AnImageWithAlphaEncodesItsColoursAndLeavesAlphaOut) {
  for (const PixelFormat format : {PixelFormat::bgra8, PixelFormat::rgba8}) {
    const ImageLayout layout = make_layout(64, 48, format);
    const auto pixels = gradient(layout);
    auto encoder = JpegEncoder::create(95);
    ASSERT_TRUE(encoder);
    ASSERT_TRUE(JpegEncoder::encodes(format));
    std::vector<std::byte> jpeg;
    ASSERT_FALSE(encoder->encode(layout, pixels, jpeg).has_value());
    auto decoder = FrameDecoder::create(make_layout(64, 48, PixelFormat::mjpeg),
                                        format == PixelFormat::bgra8 ? OutputFormat::bgr8
                                                                     : OutputFormat::rgb8);
    ASSERT_TRUE(decoder);
    std::vector<std::byte> decoded(decoder->output_layout().frame_bytes());
    ASSERT_EQ(decoder->decode(jpeg, decoded).status, DecodeStatus::ok);
    int worst = 0;
    for (std::uint32_t p = 0; p < 64 * 48; ++p) {
      for (std::uint32_t c = 0; c < 3; ++c) {  // the same three colours, in the same order
        const int a = static_cast<int>(pixels[p * 4 + c]);
        const int b = static_cast<int>(decoded[p * 3 + c]);
        worst = std::max(worst, std::abs(a - b));
      }
    }
    EXPECT_LE(worst, 24) << to_string(format);
  }
}

TEST(JpegSize, TheHeaderGivesTheSizeAndOtherBytesGetOneSentence) {
  const ImageLayout layout = make_layout(80, 24, PixelFormat::rgb8);
  auto encoder = JpegEncoder::create();
  ASSERT_TRUE(encoder);
  std::vector<std::byte> jpeg;
  ASSERT_FALSE(encoder->encode(layout, gradient(layout), jpeg).has_value());
  auto size = read_jpeg_size(jpeg);
  ASSERT_TRUE(size) << size.error().message;
  EXPECT_EQ(size->width, 80U);
  EXPECT_EQ(size->height, 24U);

  const std::vector<std::byte> png_signature = {std::byte{0x89}, std::byte{'P'}, std::byte{'N'},
                                                std::byte{'G'}};
  const auto not_jpeg = read_jpeg_size(png_signature);
  ASSERT_FALSE(not_jpeg);
  EXPECT_NE(not_jpeg.error().message.find("not a JPEG"), std::string::npos);
  EXPECT_FALSE(read_jpeg_size({}));
  EXPECT_FALSE(read_jpeg_size(std::span(jpeg).first(10)));  // cut inside the header
}

// Review of the bridge, L5: a JPEG that is only its header (no scan data) was accepted and
// published as a frame nobody can decode.
TEST(JpegSize, AHeaderWithoutScanDataIsRefusedWithOneSentence) {
  const ImageLayout layout = make_layout(64, 48, PixelFormat::rgb8);
  auto encoder = JpegEncoder::create();
  ASSERT_TRUE(encoder);
  std::vector<std::byte> jpeg;
  ASSERT_FALSE(encoder->encode(layout, gradient(layout), jpeg).has_value());
  // Find the start of scan and keep the bytes up to the end of its header.
  std::size_t sos = 0;
  for (std::size_t i = 2; i + 3 < jpeg.size(); ++i) {
    if (jpeg[i] == std::byte{0xFF} && jpeg[i + 1] == std::byte{0xDA}) {
      sos = i;
      break;
    }
  }
  ASSERT_NE(sos, 0U);
  const std::size_t header_end =
      sos + 2 + ((static_cast<std::size_t>(jpeg[sos + 2]) << 8) | static_cast<std::size_t>(jpeg[sos + 3]));
  std::vector<std::byte> header_only(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(header_end));
  const auto refused = read_jpeg_size(header_only);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("no scan data"), std::string::npos) << refused.error().message;
  header_only.push_back(std::byte{0xFF});
  header_only.push_back(std::byte{0xD9});  // a header closed by EOI is still no picture
  EXPECT_FALSE(read_jpeg_size(header_only));
  EXPECT_TRUE(read_jpeg_size(jpeg));  // the whole JPEG still passes
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
