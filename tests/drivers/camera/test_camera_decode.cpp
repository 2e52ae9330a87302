// SPDX-License-Identifier: Apache-2.0
// Every decode path against OpenCV's reference conversion, plus the cases where the decoder must
// refuse a frame (corrupt or truncated JPEG, short buffers, frames of another size).
#include <gtest/gtest.h>

#include <array>
#include <cstring>

#include "sim/imaging/decoder.hpp"
#include "sim/imaging/image_format.hpp"
#include "test_images.hpp"

namespace sim::camera {
namespace {

using testing::Bytes;

struct Case {
  PixelFormat input;
  imaging::OutputFormat output;
  std::uint32_t padding;  // bytes of row padding in the input
};

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  return std::string(sim::to_string(info.param.input)) + "_to_" + to_string(info.param.output) +
         (info.param.padding != 0 ? "_padded" : "");
}

class PackedDecode : public ::testing::TestWithParam<Case> {};

TEST_P(PackedDecode, MatchesOpenCvIntoAStridedSlot) {
  const Case c = GetParam();
  constexpr std::uint32_t width = 64;
  constexpr std::uint32_t height = 36;
  const ImageLayout input =
      imaging::make_layout(width, height, c.input,
                  static_cast<std::uint32_t>(imaging::row_bytes(width, c.input)) + c.padding);
  const Bytes source = c.input == PixelFormat::bgr8 ? testing::scene_bgr(width, height, 3)
                                                    : testing::noise(input.frame_bytes(), 7);
  auto decoder = imaging::FrameDecoder::create(input, c.output);
  ASSERT_TRUE(decoder) << decoder.error().message;

  // The destination is larger than a frame and poisoned: exactly frame_bytes() must be written.
  Bytes slot(decoder->output_capacity(0) + 64, std::byte{0xEE});
  const imaging::DecodeResult result = decoder->decode(source, slot);
  ASSERT_EQ(result.status, imaging::DecodeStatus::ok);
  ASSERT_EQ(result.size, decoder->output_layout().frame_bytes());
  EXPECT_EQ(slot[result.size], std::byte{0xEE});

  if (c.output == imaging::OutputFormat::raw) {
    EXPECT_EQ(decoder->output_layout(), input);
    EXPECT_TRUE(std::equal(source.begin(), source.end(), slot.begin()));
    return;
  }
  const Bytes expected = testing::reference(input, source, c.output);
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(decoder->output_layout().format, imaging::output_pixel_format(c.output, c.input));
  EXPECT_EQ(testing::max_difference(std::span(slot).first(result.size), expected), 0);
}

INSTANTIATE_TEST_SUITE_P(
    AllPackedPaths, PackedDecode,
    ::testing::Values(Case{PixelFormat::yuyv, imaging::OutputFormat::bgr8, 0},
                      Case{PixelFormat::yuyv, imaging::OutputFormat::rgb8, 0},
                      Case{PixelFormat::yuyv, imaging::OutputFormat::mono8, 0},
                      Case{PixelFormat::yuyv, imaging::OutputFormat::bgr8, 32},
                      Case{PixelFormat::yuyv, imaging::OutputFormat::raw, 32},
                      Case{PixelFormat::uyvy, imaging::OutputFormat::bgr8, 0},
                      Case{PixelFormat::uyvy, imaging::OutputFormat::rgb8, 16},
                      Case{PixelFormat::uyvy, imaging::OutputFormat::mono8, 0},
                      Case{PixelFormat::mono8, imaging::OutputFormat::mono8, 8},
                      Case{PixelFormat::mono8, imaging::OutputFormat::bgr8, 0},
                      Case{PixelFormat::mono16, imaging::OutputFormat::mono8, 0},
                      Case{PixelFormat::mono16, imaging::OutputFormat::bgr8, 4},
                      Case{PixelFormat::mono16, imaging::OutputFormat::raw, 0},
                      Case{PixelFormat::bgr8, imaging::OutputFormat::bgr8, 0},
                      Case{PixelFormat::bgr8, imaging::OutputFormat::rgb8, 0},
                      Case{PixelFormat::bgr8, imaging::OutputFormat::mono8, 0}),
    case_name);

// Not only "the same call as OpenCV": the colours must be right.
TEST(Decode, YuyvRedIsRedInBgrAndRgb) {
  // BT.601 red: Y 81, U 90, V 240.
  Bytes yuyv;
  for (int i = 0; i < 8 * 4 / 2; ++i) {
    for (const int v : {81, 90, 81, 240}) yuyv.push_back(static_cast<std::byte>(v));
  }
  const ImageLayout input = imaging::make_layout(8, 4, PixelFormat::yuyv);
  std::array<std::byte, 8 * 4 * 3> out{};
  auto bgr = imaging::FrameDecoder::create(input, imaging::OutputFormat::bgr8);
  ASSERT_EQ(bgr->decode(yuyv, out).status, imaging::DecodeStatus::ok);
  EXPECT_LT(static_cast<int>(out[0]), 20);   // B
  EXPECT_GT(static_cast<int>(out[2]), 230);  // R
  auto rgb = imaging::FrameDecoder::create(input, imaging::OutputFormat::rgb8);
  ASSERT_EQ(rgb->decode(yuyv, out).status, imaging::DecodeStatus::ok);
  EXPECT_GT(static_cast<int>(out[0]), 230);  // R first
}

// GenICam BayerRG8 / V4L2 RGGB must come out red for a red scene (OpenCV names it BayerBG).
TEST(Decode, BayerPatternsGiveTheRightColour) {
  constexpr std::uint32_t w = 16;
  constexpr std::uint32_t h = 16;
  struct Pattern {
    PixelFormat format;
    int red_x;  // where the red sample sits in the 2×2 cell (row 0)
    int red_y;
  };
  for (const Pattern p : {Pattern{PixelFormat::bayer_rggb8, 0, 0},
                          Pattern{PixelFormat::bayer_bggr8, 1, 1},
                          Pattern{PixelFormat::bayer_gbrg8, 0, 1},
                          Pattern{PixelFormat::bayer_grbg8, 1, 0}}) {
    Bytes mosaic(w * h, std::byte{0});
    for (std::uint32_t y = 0; y < h; ++y) {
      for (std::uint32_t x = 0; x < w; ++x) {
        if (static_cast<int>(x % 2) == p.red_x && static_cast<int>(y % 2) == p.red_y) {
          mosaic[y * w + x] = std::byte{255};
        }
      }
    }
    auto decoder = imaging::FrameDecoder::create(imaging::make_layout(w, h, p.format), imaging::OutputFormat::bgr8);
    ASSERT_TRUE(decoder);
    Bytes out(w * h * 3);
    ASSERT_EQ(decoder->decode(mosaic, out).status, imaging::DecodeStatus::ok);
    const std::size_t centre = (8 * w + 8) * 3;
    EXPECT_EQ(static_cast<int>(out[centre + 0]), 0) << sim::to_string(p.format);
    EXPECT_EQ(static_cast<int>(out[centre + 1]), 0) << sim::to_string(p.format);
    EXPECT_EQ(static_cast<int>(out[centre + 2]), 255) << sim::to_string(p.format);
  }
}

class JpegDecode : public ::testing::TestWithParam<std::pair<std::uint32_t, std::uint32_t>> {};

TEST_P(JpegDecode, MatchesImdecodeInEveryOutput) {
  const auto [width, height] = GetParam();
  const Bytes jpeg = testing::encode_jpeg(testing::scene_bgr(width, height, 5), width, height);
  const ImageLayout input = imaging::make_layout(width, height, PixelFormat::mjpeg);
  for (const auto output : {imaging::OutputFormat::bgr8, imaging::OutputFormat::rgb8, imaging::OutputFormat::mono8}) {
    auto decoder = imaging::FrameDecoder::create(input, output);
    ASSERT_TRUE(decoder) << decoder.error().message;
    Bytes slot(decoder->output_capacity(0));
    const imaging::DecodeResult result = decoder->decode(jpeg, slot);
    ASSERT_EQ(result.status, imaging::DecodeStatus::ok) << to_string(output);
    ASSERT_EQ(result.size, slot.size());
    const Bytes expected = testing::reference(input, jpeg, output);
    // Same libjpeg-turbo, same IDCT and upsampling: at most rounding differences.
    EXPECT_LE(testing::max_difference(slot, expected), 1) << to_string(output);
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, JpegDecode,
                         ::testing::Values(std::pair<std::uint32_t, std::uint32_t>{64, 48},
                                           std::pair<std::uint32_t, std::uint32_t>{70, 38},
                                           std::pair<std::uint32_t, std::uint32_t>{640, 480}));

TEST(Decode, JpegPassThroughKeepsTheBytes) {
  const Bytes jpeg = testing::encode_jpeg(testing::scene_bgr(64, 48, 1), 64, 48);
  auto decoder = imaging::FrameDecoder::create(imaging::make_layout(64, 48, PixelFormat::mjpeg), imaging::OutputFormat::raw);
  ASSERT_TRUE(decoder);
  EXPECT_EQ(decoder->output_layout().format, PixelFormat::mjpeg);
  EXPECT_EQ(decoder->output_capacity(10000), 10000u);
  Bytes slot(10000);
  const imaging::DecodeResult result = decoder->decode(jpeg, slot);
  ASSERT_EQ(result.status, imaging::DecodeStatus::ok);
  ASSERT_EQ(result.size, jpeg.size());
  EXPECT_TRUE(std::equal(jpeg.begin(), jpeg.end(), slot.begin()));
  Bytes small(jpeg.size() - 1);
  EXPECT_EQ(decoder->decode(jpeg, small).status, imaging::DecodeStatus::output_too_small);
  // A pass-through still refuses what is not a JPEG of the negotiated size.
  EXPECT_EQ(decoder->decode(testing::noise(500, 1), slot).status, imaging::DecodeStatus::corrupt_input);
  const Bytes other = testing::encode_jpeg(testing::scene_bgr(32, 48, 1), 32, 48);
  EXPECT_EQ(decoder->decode(other, slot).status, imaging::DecodeStatus::wrong_size);
}

TEST(Decode, CorruptJpegIsRefused) {
  const Bytes jpeg = testing::encode_jpeg(testing::scene_bgr(64, 48, 2), 64, 48);
  auto decoder = imaging::FrameDecoder::create(imaging::make_layout(64, 48, PixelFormat::mjpeg), imaging::OutputFormat::bgr8);
  ASSERT_TRUE(decoder);
  Bytes slot(64 * 48 * 3);

  // Cut anywhere after the header: libjpeg would fill the rest with grey and only warn.
  for (const std::size_t keep : {jpeg.size() / 2, jpeg.size() - 10, std::size_t{700}}) {
    const Bytes truncated(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(keep));
    EXPECT_EQ(decoder->decode(truncated, slot).status, imaging::DecodeStatus::corrupt_input) << keep;
  }
  EXPECT_EQ(decoder->decode({}, slot).status, imaging::DecodeStatus::corrupt_input);
  EXPECT_EQ(decoder->decode(testing::noise(4000, 9), slot).status, imaging::DecodeStatus::corrupt_input);
  Bytes header_only(jpeg.begin(), jpeg.begin() + 200);
  EXPECT_NE(decoder->decode(header_only, slot).status, imaging::DecodeStatus::ok);

  // A frame of another size would overflow the slot: refused before decoding.
  const Bytes bigger = testing::encode_jpeg(testing::scene_bgr(128, 96, 2), 128, 96);
  EXPECT_EQ(decoder->decode(bigger, slot).status, imaging::DecodeStatus::wrong_size);
  // And a good frame still decodes after all that.
  EXPECT_EQ(decoder->decode(jpeg, slot).status, imaging::DecodeStatus::ok);
}

TEST(Decode, ShortPackedFramesAndSmallSlotsAreRefused) {
  const ImageLayout input = imaging::make_layout(64, 36, PixelFormat::yuyv);
  auto decoder = imaging::FrameDecoder::create(input, imaging::OutputFormat::bgr8);
  ASSERT_TRUE(decoder);
  const Bytes frame = testing::noise(input.frame_bytes(), 1);
  Bytes slot(64 * 36 * 3);
  EXPECT_EQ(decoder->decode(std::span(frame).first(frame.size() - 1), slot).status,
            imaging::DecodeStatus::short_input);
  EXPECT_EQ(decoder->decode(frame, std::span(slot).first(slot.size() - 1)).status,
            imaging::DecodeStatus::output_too_small);
  EXPECT_EQ(decoder->decode(frame, slot).status, imaging::DecodeStatus::ok);
}

TEST(Decode, UnsupportedConversionsAreRefusedWithASentence) {
  auto odd = imaging::FrameDecoder::create(imaging::make_layout(63, 10, PixelFormat::yuyv), imaging::OutputFormat::bgr8);
  ASSERT_FALSE(odd);
  EXPECT_NE(odd.error().message.find("even width"), std::string::npos);
  auto unknown = imaging::FrameDecoder::create(imaging::make_layout(64, 10, PixelFormat::unknown), imaging::OutputFormat::bgr8);
  ASSERT_FALSE(unknown);
  auto empty = imaging::FrameDecoder::create(imaging::make_layout(0, 10, PixelFormat::mono8), imaging::OutputFormat::bgr8);
  ASSERT_FALSE(empty);
  EXPECT_FALSE(empty.error().message.empty());
}

TEST(ImageFormat, LayoutsAndNames) {
  const ImageLayout padded = imaging::make_layout(640, 480, PixelFormat::yuyv, 1344);
  EXPECT_EQ(padded.stride, 1344u);
  EXPECT_EQ(padded.channels, 2u);
  EXPECT_EQ(imaging::min_input_bytes(padded), 1344u * 479 + 1280);
  EXPECT_EQ(imaging::make_layout(640, 480, PixelFormat::bgr8).stride, 1920u);
  EXPECT_EQ(imaging::make_layout(640, 480, PixelFormat::mono16).bit_depth, 16u);
  EXPECT_EQ(imaging::make_layout(640, 480, PixelFormat::mjpeg).stride, 0u);
  EXPECT_EQ(imaging::parse_output_format("mono8"), imaging::OutputFormat::mono8);
  EXPECT_FALSE(imaging::parse_output_format("bgr"));
  // Our layouts are the ones the core accepts.
  EXPECT_EQ(Layout::of(imaging::make_layout(640, 480, PixelFormat::rgb8)).check(640 * 480 * 3), "");
  EXPECT_EQ(imaging::make_layout(640, 480, PixelFormat::rgb8), ImageLayout::packed(640, 480, PixelFormat::rgb8));
}

}  // namespace
}  // namespace sim::camera
