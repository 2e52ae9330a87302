// SPDX-License-Identifier: Apache-2.0
// sim_dump as a real process on image streams: the PNG it writes must hold the frame's pixels,
// as they are for formats PNG stores (mono8, mono16, bgr8) and as OpenCV's reference conversion
// to BGR for the others (rgb8, YUYV, Bayer, MJPEG).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "sim/apps/camera_info_file.hpp"
#include "sim/sim.hpp"
#include "sim_test/process.hpp"
#include "test_images.hpp"

namespace {

namespace fs = std::filesystem;
using sim::ImageLayout;
using sim::PixelFormat;
using sim::imaging::OutputFormat;
using sim::camera::testing::Bytes;
using sim::testing::run;

constexpr std::uint32_t kWidth = 64;
constexpr std::uint32_t kHeight = 48;

class DumpPng : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string id = std::to_string(getpid()) + "_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    stream_ = "/test_dump_png_" + id;
    dir_ = fs::temp_directory_path() / ("test_dump_png_" + id);
    fs::remove_all(dir_);
  }
  void TearDown() override {
    (void)sim::destroy(stream_, true);
    fs::remove_all(dir_);
  }

  // Publishes `frame` as one image of `layout` (capacity: `capacity` or the layout's), dumps it
  // with sim_dump and returns the PNG as OpenCV reads it back, unchanged.
  cv::Mat publish_and_dump(const ImageLayout& layout, const Bytes& frame, std::uint64_t capacity = 0) {
    auto writer = sim::Writer::create({.name = stream_, .capacity = capacity, .layout = sim::Layout::of(layout)});
    EXPECT_TRUE(writer) << writer.error().message;
    if (!writer) return {};
    EXPECT_EQ(writer->write(std::span<const std::byte>(frame), 42), sim::WriteStatus::ok);
    const auto result = run({SIM_DUMP, stream_, "--current", "--count", "1", "--out", dir_.string()});
    EXPECT_EQ(result.code, 0) << result.err;
    const fs::path png = dir_ / (stream_.substr(1) + "_00000001.png");
    EXPECT_TRUE(fs::exists(png)) << result.out << result.err;
    EXPECT_TRUE(fs::exists(dir_ / (stream_.substr(1) + "_00000001.json")));
    return cv::imread(png.string(), cv::IMREAD_UNCHANGED);
  }

  std::string stream_;
  fs::path dir_;
};

Bytes bytes_of(const cv::Mat& image) {
  const cv::Mat packed = image.isContinuous() ? image : image.clone();
  const auto* p = reinterpret_cast<const std::byte*>(packed.data);
  return Bytes(p, p + packed.total() * packed.elemSize());
}

TEST_F(DumpPng, FormatsPngHoldsAreWrittenBitExact) {
  const Bytes bgr = sim::camera::testing::scene_bgr(kWidth, kHeight, 1);
  const cv::Mat written = publish_and_dump(ImageLayout::packed(kWidth, kHeight, PixelFormat::bgr8), bgr);
  ASSERT_EQ(written.type(), CV_8UC3);
  EXPECT_EQ(bytes_of(written), bgr);
}

TEST_F(DumpPng, SixteenBitMonoKeepsItsDepth) {
  const Bytes y16 = sim::camera::testing::noise(kWidth * kHeight * 2, 7);
  const cv::Mat written = publish_and_dump(ImageLayout::packed(kWidth, kHeight, PixelFormat::mono16), y16);
  ASSERT_EQ(written.type(), CV_16UC1);
  EXPECT_EQ(bytes_of(written), y16);
}

TEST_F(DumpPng, OtherFormatsAreConvertedToBgrLikeOpenCv) {
  for (const PixelFormat format : {PixelFormat::rgb8, PixelFormat::yuyv, PixelFormat::bayer_rggb8}) {
    SCOPED_TRACE(sim::to_string(format));
    TearDown();
    const ImageLayout layout = ImageLayout::packed(kWidth, kHeight, format);
    const Bytes input = sim::camera::testing::noise(layout.frame_bytes(), 3);
    const cv::Mat written = publish_and_dump(layout, input);
    ASSERT_EQ(written.type(), CV_8UC3);
    const Bytes expected = sim::camera::testing::reference(layout, input, OutputFormat::bgr8);
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(sim::camera::testing::max_difference(bytes_of(written), expected), 0);
  }
}

TEST_F(DumpPng, MjpegFramesAreDecoded) {
  const Bytes bgr = sim::camera::testing::scene_bgr(kWidth, kHeight, 5);
  const Bytes jpeg = sim::camera::testing::encode_jpeg(bgr, kWidth, kHeight);
  ImageLayout layout;
  layout.width = kWidth;
  layout.height = kHeight;
  layout.format = PixelFormat::mjpeg;
  const cv::Mat written = publish_and_dump(layout, jpeg, 64 * 1024);
  ASSERT_EQ(written.type(), CV_8UC3);
  const Bytes expected = sim::camera::testing::reference(layout, jpeg, OutputFormat::bgr8);
  ASSERT_FALSE(expected.empty());
  // libjpeg-turbo against OpenCV's JPEG decoder: the same codec family, not always the same IDCT.
  EXPECT_LE(sim::camera::testing::max_difference(bytes_of(written), expected), 3);
}

TEST_F(DumpPng, CorruptJpegIsAClearErrorAndNoFile) {
  ImageLayout layout;
  layout.width = kWidth;
  layout.height = kHeight;
  layout.format = PixelFormat::mjpeg;
  auto writer = sim::Writer::create({.name = stream_, .capacity = 4096, .layout = sim::Layout::of(layout)});
  ASSERT_TRUE(writer) << writer.error().message;
  const Bytes garbage = sim::camera::testing::noise(1000, 9);
  ASSERT_EQ(writer->write(std::span<const std::byte>(garbage), 1), sim::WriteStatus::ok);
  const auto result = run({SIM_DUMP, stream_, "--current", "--count", "1", "--out", dir_.string()});
  EXPECT_EQ(result.code, 1);
  EXPECT_NE(result.err.find("does not decode"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(dir_ / (stream_.substr(1) + "_00000001.png")));
}

}  // namespace

namespace {

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST_F(DumpPng, WritesTheCalibrationBesideTheImageAndTheTransformInTheSidecar) {
  sim::SensorInfo sensor;
  sensor.frame_id = "camera_front_optical";
  sensor.parent_frame = "base_link";
  sensor.mounting = sim::Mounting::from_xyz_rpy(1.5, -0.25, 1.2, -1.5707963, 0, -1.5707963);
  sim::CameraCalibration c;
  c.width = kWidth;
  c.height = kHeight;
  c.camera_name = "front";
  c.d = {-0.28, 0.07, 0.0004, -0.0003, 0.0};
  c.k = {50.5, 0, 32.25, 0, 51.0, 24.5, 0, 0, 1};
  c.p = {50.5, 0, 32.25, 0, 0, 51.0, 24.5, 0, 0, 0, 1, 0};
  sensor.calibration = c;
  const ImageLayout layout = ImageLayout::packed(kWidth, kHeight, PixelFormat::bgr8);
  auto writer = sim::Writer::create({.name = stream_, .layout = sim::Layout::of(layout), .sensor = sensor});
  ASSERT_TRUE(writer) << writer.error().message;
  const Bytes bgr = sim::camera::testing::scene_bgr(kWidth, kHeight, 1);
  ASSERT_EQ(writer->write(std::span<const std::byte>(bgr), 42), sim::WriteStatus::ok);
  const auto result = run({SIM_DUMP, stream_, "--current", "--count", "1", "--out", dir_.string()});
  ASSERT_EQ(result.code, 0) << result.err;

  const std::string stem = stream_.substr(1) + "_00000001";
  const fs::path yaml = dir_ / (stem + ".yaml");
  ASSERT_TRUE(fs::exists(yaml));
  const std::string text = text_of(yaml);
  for (const char* key : {"image_width: 64", "image_height: 48", "camera_matrix:", "rows: 3",
                          "distortion_model: \"plumb_bob\"", "projection_matrix:"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << " in\n" << text;
  }
  auto back = sim::apps::load_camera_info(yaml.string());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(*back == c);

  const std::string sidecar = text_of(dir_ / (stem + ".json"));
  EXPECT_NE(sidecar.find("\"frame_id\": \"camera_front_optical\""), std::string::npos) << sidecar;
  EXPECT_NE(sidecar.find("\"transform\": {\"parent_frame\": \"base_link\", \"child_frame\": "
                         "\"camera_front_optical\", \"translation\": [1.5, -0.25, 1.2]"),
            std::string::npos)
      << sidecar;
  char rotation[160];
  const auto& r = sensor.mounting->rotation;
  std::snprintf(rotation, sizeof rotation, "\"rotation\": [%.17g, %.17g, %.17g, %.17g]", r[0], r[1],
                r[2], r[3]);
  EXPECT_NE(sidecar.find(rotation), std::string::npos) << sidecar;
  EXPECT_NE(sidecar.find("\"calibration_file\": \"" + stem + ".yaml\""), std::string::npos) << sidecar;
}

TEST_F(DumpPng, AStreamWithoutADescriptionGetsNoCalibrationFileAndANullTransform) {
  const Bytes bgr = sim::camera::testing::scene_bgr(kWidth, kHeight, 1);
  (void)publish_and_dump(ImageLayout::packed(kWidth, kHeight, PixelFormat::bgr8), bgr);
  const std::string stem = stream_.substr(1) + "_00000001";
  EXPECT_FALSE(fs::exists(dir_ / (stem + ".yaml")));
  const std::string sidecar = text_of(dir_ / (stem + ".json"));
  EXPECT_NE(sidecar.find("\"transform\": null"), std::string::npos) << sidecar;
}
