// SPDX-License-Identifier: Apache-2.0
// The camera_calibration_parsers YAML file: read into every field, written so it reads back
// exactly, and every kind of bad file refused with one sentence.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "sim/apps/camera_info_file.hpp"

namespace {

using sim::CameraCalibration;
using sim::apps::format_camera_info;
using sim::apps::load_camera_info;
using sim::apps::parse_camera_info;

const std::string kFront = std::string(SIM_APPS_TEST_DATA) + "/camera_front.yaml";

// Text of a valid file with one line replaced, to break one thing at a time.
std::string front_with(const std::string& key, const std::string& line) {
  std::ifstream in(kFront);
  std::string text, current;
  bool skipping = false;
  while (std::getline(in, current)) {
    if (current.rfind(key + ":", 0) == 0) {
      text += line + "\n";
      skipping = true;  // and the matrix lines under it
      continue;
    }
    if (skipping && current.rfind("  ", 0) == 0) continue;
    skipping = false;
    text += current + "\n";
  }
  return text;
}

void expect_one_sentence(const sim::Error& error, const std::string& part) {
  EXPECT_EQ(error.code, sim::ErrorCode::invalid_argument);
  EXPECT_NE(error.message.find(part), std::string::npos) << error.message;
  EXPECT_EQ(error.message.find('\n'), std::string::npos) << error.message;
}

TEST(CameraInfoFile, ReadsACameracalibratorFileIntoEveryField) {
  auto c = load_camera_info(kFront);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->width, 768U);
  EXPECT_EQ(c->height, 576U);
  EXPECT_EQ(c->camera_name, "camera_front");
  EXPECT_EQ(c->distortion_model, "plumb_bob");
  EXPECT_EQ(c->k[0], 612.4471435546875);
  EXPECT_EQ(c->k[2], 383.21);
  EXPECT_EQ(c->k[4], 613.0023);
  EXPECT_EQ(c->k[5], 291.75);
  EXPECT_EQ(c->k[8], 1.0);
  ASSERT_EQ(c->d.size(), 5U);
  EXPECT_EQ(c->d[0], -0.2811);
  EXPECT_EQ(c->d[3], -0.00031);
  EXPECT_EQ(c->r[4], 1.0);
  EXPECT_EQ(c->r[1], 0.0);
  EXPECT_EQ(c->p[6], 291.75);
  EXPECT_EQ(c->p[10], 1.0);
  EXPECT_EQ(c->binning_x, 0U);
  EXPECT_EQ(c->roi.width, 0U);
}

TEST(CameraInfoFile, AFileUrlNamesTheSameFile) {
  auto c = load_camera_info("file://" + std::filesystem::absolute(kFront).string());
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->width, 768U);
  auto package = load_camera_info("package://camera/front.yaml");
  ASSERT_FALSE(package);
  expect_one_sentence(package.error(), "file://");
}

TEST(CameraInfoFile, AMissingDistortionModelMeansPlumbBobAndAMissingNameIsEmpty) {
  std::string text = front_with("distortion_model", "");
  text = text.substr(0, text.find("camera_name")) + text.substr(text.find("camera_matrix"));
  auto c = parse_camera_info(text);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->distortion_model, "plumb_bob");
  EXPECT_EQ(c->camera_name, "");
}

TEST(CameraInfoFile, AWrittenFileReadsBackExactly) {
  CameraCalibration c;
  c.width = 1920;
  c.height = 1200;
  c.camera_name = "left \"wide\" \\ lens";
  c.distortion_model = "rational_polynomial";
  c.d = {0.1, -0.2, 1e-300, 2.0 / 3.0, 0.01, 0.3, -0.1, 0.05};
  c.k = {1000.5, 0, 960.25, 0, 1001.0 / 3.0, 600, 0, 0, 1};
  c.r = {0.9999, 0.001, 0, -0.001, 0.9999, 0, 0, 0, 1};
  c.p = {1000.5, 0, 960.25, -60.1, 0, 1001.0 / 3.0, 600, 0, 0, 0, 1, 0};
  c.binning_x = 2;
  c.binning_y = 2;
  c.roi = {8, 4, 1100, 1800, true};
  auto back = parse_camera_info(format_camera_info(c));
  ASSERT_TRUE(back) << back.error().message << "\n" << format_camera_info(c);
  EXPECT_TRUE(*back == c) << format_camera_info(c);

  const std::string file = "/tmp/sim_camera_info_" + std::to_string(::getpid()) + ".yaml";
  ASSERT_TRUE(sim::apps::save_camera_info(file, c));
  auto loaded = load_camera_info(file);
  std::filesystem::remove(file);
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_TRUE(*loaded == c);
}

TEST(CameraInfoFile, AMatrixOfTheWrongSizeIsRefusedWithOneSentence) {
  auto wrong_shape = parse_camera_info(front_with(
      "camera_matrix", "camera_matrix: {rows: 3, cols: 4, data: [1,0,0,0, 0,1,0,0, 0,0,1,0]}"));
  ASSERT_FALSE(wrong_shape);
  expect_one_sentence(wrong_shape.error(), "'camera_matrix' is 3x4, not 3x3");

  auto short_data = parse_camera_info(front_with(
      "projection_matrix", "projection_matrix: {rows: 3, cols: 4, data: [1, 0, 2, 0, 0, 1]}"));
  ASSERT_FALSE(short_data);
  expect_one_sentence(short_data.error(), "'projection_matrix' has 6 numbers for 3x4");

  // Review turn 4 L7: D as a column is read as camera_calibration_parsers reads it.
  auto d_column = parse_camera_info(front_with(
      "distortion_coefficients", "distortion_coefficients: {rows: 5, cols: 1, data: [0.5,0,0,0,0.25]}"));
  ASSERT_TRUE(d_column) << d_column.error().message;
  EXPECT_EQ(d_column->d, (std::vector<double>{0.5, 0, 0, 0, 0.25}));
  // A camera_name longer than the record is cut, not a reason to refuse the file.
  auto long_name = parse_camera_info(front_with("camera_name", "camera_name: " + std::string(80, 'n')));
  ASSERT_TRUE(long_name) << long_name.error().message;
  EXPECT_EQ(long_name->camera_name, std::string(63, 'n'));

  auto too_many = parse_camera_info(front_with(
      "distortion_coefficients",
      "distortion_coefficients: {rows: 1, cols: 17, data: [0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}"));
  ASSERT_FALSE(too_many);
  expect_one_sentence(too_many.error(), "17 distortion coefficients");
}

TEST(CameraInfoFile, ANumberThatIsNotFiniteIsRefusedWithOneSentence) {
  for (const char* bad : {".nan", ".inf", "-.Inf", "1e999"}) {
    auto c = parse_camera_info(front_with(
        "camera_matrix", std::string("camera_matrix: {rows: 3, cols: 3, data: [") + bad +
                             ", 0, 383, 0, 613, 291, 0, 0, 1]}"));
    ASSERT_FALSE(c) << bad;
    expect_one_sentence(c.error(), "'camera_matrix' entry 1");
  }
  auto word = parse_camera_info(front_with(
      "rectification_matrix", "rectification_matrix: {rows: 3, cols: 3, data: [1,0,0,0,one,0,0,0,1]}"));
  ASSERT_FALSE(word);
  expect_one_sentence(word.error(), "entry 5");
}

// Review turn 4 L7: fx = fy = 1e308 and an R that is not a rotation were read and published.
TEST(CameraInfoFile, NumbersNoCameraHasAreRefusedWithOneSentenceThatSaysWhatToDo) {
  for (const char* focal : {"1e308, 0, 383, 0, 1e308", "-612, 0, 383, 0, 613", "612, 0, 383, 0, 0"}) {
    auto c = parse_camera_info(front_with(
        "camera_matrix", std::string("camera_matrix: {rows: 3, cols: 3, data: [") + focal + ", 291, 0, 0, 1]}"));
    ASSERT_FALSE(c) << focal;
    expect_one_sentence(c.error(), "in 'camera_matrix', which no 768x576 camera has");
    expect_one_sentence(c.error(), "calibrate the camera again or fix the file");
  }
  for (const char* r : {"2, 0, 0, 0, 1, 0, 0, 0, 1", "-1, 0, 0, 0, 1, 0, 0, 0, 1", "1, 0.5, 0, 0, 1, 0, 0, 0, 1"}) {
    auto c = parse_camera_info(front_with(
        "rectification_matrix", std::string("rectification_matrix: {rows: 3, cols: 3, data: [") + r + "]}"));
    ASSERT_FALSE(c) << r;
    expect_one_sentence(c.error(), "'rectification_matrix' that is not a rotation");
  }
  // What real files hold is read: a rotated R (stereo rectification), an uncalibrated camera's
  // zeros, R of zeros.
  for (const auto& [key, line] : std::vector<std::pair<std::string, std::string>>{
           {"rectification_matrix",
            "rectification_matrix: {rows: 3, cols: 3, data: [0.9998, 0.0175, 0, -0.0175, 0.9998, 0, 0, 0, 1]}"},
           {"camera_matrix", "camera_matrix: {rows: 3, cols: 3, data: [0, 0, 0, 0, 0, 0, 0, 0, 0]}"},
           {"rectification_matrix", "rectification_matrix: {rows: 3, cols: 3, data: [0, 0, 0, 0, 0, 0, 0, 0, 0]}"}}) {
    auto c = parse_camera_info(front_with(key, line));
    EXPECT_TRUE(c) << line << ": " << c.error().message;
  }
}

TEST(CameraInfoFile, AMalformedFileIsRefusedWithOneSentence) {
  auto broken = parse_camera_info("image_width: [\n");
  ASSERT_FALSE(broken);
  expect_one_sentence(broken.error(), "not valid YAML");

  auto list = parse_camera_info("- 1\n- 2\n");
  ASSERT_FALSE(list);
  expect_one_sentence(list.error(), "not a map");

  auto no_matrix = parse_camera_info("image_width: 640\nimage_height: 480\n");
  ASSERT_FALSE(no_matrix);
  expect_one_sentence(no_matrix.error(), "has no 'camera_matrix'");

  auto zero = parse_camera_info(front_with("image_width", "image_width: 0"));
  ASSERT_FALSE(zero);
  expect_one_sentence(zero.error(), "size of zero");

  auto negative = parse_camera_info(front_with("image_height", "image_height: -576"));
  ASSERT_FALSE(negative);
  expect_one_sentence(negative.error(), "'image_height'");

  auto missing = load_camera_info("/nonexistent/camera.yaml");
  ASSERT_FALSE(missing);
  expect_one_sentence(missing.error(), "/nonexistent/camera.yaml");
}

}  // namespace
