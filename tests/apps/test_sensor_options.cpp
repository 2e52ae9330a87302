// SPDX-License-Identifier: Apache-2.0
// The sensor options every driver and replay takes: frame, parent, static_transform_publisher's
// mounting, --camera-info; the same keys in a config file; and every bad value a usage error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/apps/sensor_options.hpp"

namespace {

using sim::apps::CommandLine;
using sim::apps::SensorKind;
using sim::apps::SensorOptions;

const std::string kData = SIM_APPS_TEST_DATA;

std::optional<int> parse(CommandLine& cli, std::vector<std::string> words) {
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return cli.parse(static_cast<int>(argv.size()), argv.data());
}

// A folder of its own that removes itself.
class TempFolder {
 public:
  TempFolder() : path_("/tmp/sim_sensor_options_" + std::to_string(::getpid())) {
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name, const std::string& text) const {
    const std::string path = path_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }

 private:
  std::string path_;
};

TEST(SensorOptions, TheOptionsGiveTheFrameTheParentAndStaticTransformPublishersMounting) {
  CommandLine cli("sim_test", "test");
  SensorOptions options;
  sim::apps::add_sensor_options(cli, options, SensorKind::lidar);
  ASSERT_FALSE(parse(cli, {"sim_test", "--frame-id", "lidar_top", "--parent-frame", "roof",
                           "--x", "1.5", "--z", "-0.25", "--yaw", std::to_string(M_PI / 2)}));
  auto info = sim::apps::sensor_info_from(options, "/lidar");
  ASSERT_TRUE(info) << info.error().message;
  EXPECT_EQ(info->frame_id, "lidar_top");
  EXPECT_EQ(info->parent_frame, "roof");
  ASSERT_TRUE(info->mounting.has_value());
  EXPECT_EQ(info->mounting->translation, (std::array<double, 3>{1.5, 0.0, -0.25}));
  // A quarter turn about z: (x, y, z, w) = (0, 0, sin 45°, cos 45°).
  EXPECT_NEAR(info->mounting->rotation[0], 0.0, 1e-6);
  EXPECT_NEAR(info->mounting->rotation[1], 0.0, 1e-6);
  EXPECT_NEAR(info->mounting->rotation[2], std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(info->mounting->rotation[3], std::sqrt(0.5), 1e-6);
  EXPECT_FALSE(info->calibration.has_value());
}

TEST(SensorOptions, WithoutOptionsTheFrameComesFromTheStreamAndTheMountingIsUnknown) {
  CommandLine cli("sim_test", "test");
  SensorOptions options;
  sim::apps::add_sensor_options(cli, options, SensorKind::lidar);
  ASSERT_FALSE(parse(cli, {"sim_test"}));
  auto info = sim::apps::sensor_info_from(options, "/camera.front-left");
  ASSERT_TRUE(info) << info.error().message;
  EXPECT_EQ(info->frame_id, "camera_front_left");
  EXPECT_EQ(info->parent_frame, "base_link");
  EXPECT_FALSE(info->mounting.has_value());
  EXPECT_EQ(sim::apps::default_frame_id("/3d"), "sensor_3d");
}

TEST(SensorOptions, TheSameKeysInAConfigFileGiveTheSameDescription) {
  TempFolder folder;
  std::ifstream in(kData + "/camera_front.yaml");
  const std::string calibration((std::istreambuf_iterator<char>(in)), {});
  folder.file("front.yaml", calibration);
  const std::string config = folder.file(
      "camera.yaml",
      "frame_id: camera_front_optical\nparent_frame: base_link\nx: 2.0\npitch: 0.1\n"
      "camera_info: front.yaml\n");  // relative to the config file's folder
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  SensorOptions options;
  sim::apps::add_sensor_options(cli, options, SensorKind::camera);
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", config, "--x", "3"}));  // the command line wins
  auto info = sim::apps::sensor_info_from(options, "/camera_front");
  ASSERT_TRUE(info) << info.error().message;
  EXPECT_EQ(info->frame_id, "camera_front_optical");
  ASSERT_TRUE(info->mounting.has_value());
  EXPECT_EQ(info->mounting->translation[0], 3.0);
  const auto expected = sim::Mounting::from_xyz_rpy(3.0, 0, 0, 0, 0.1, 0);
  EXPECT_EQ(info->mounting->rotation, expected.rotation);
  ASSERT_TRUE(info->calibration.has_value());
  EXPECT_EQ(info->calibration->width, 768U);
  EXPECT_EQ(info->calibration_source.rfind("file:///", 0), 0U) << info->calibration_source;
  EXPECT_NE(info->calibration_source.find("front.yaml"), std::string::npos);
  EXPECT_TRUE(sim::apps::check_calibration_size(*info, 768, 576));
}

TEST(SensorOptions, AFileUrlInAConfigFileIsKeptAsItIs) {
  TempFolder folder;
  const std::string url = "file://" + std::filesystem::absolute(kData + "/camera_front.yaml").string();
  const std::string config = folder.file("camera.yaml", "camera_info: " + url + "\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  SensorOptions options;
  sim::apps::add_sensor_options(cli, options, SensorKind::camera);
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", config}));
  EXPECT_EQ(options.camera_info, url);
  auto info = sim::apps::sensor_info_from(options, "/camera_front");
  ASSERT_TRUE(info) << info.error().message;
  EXPECT_TRUE(info->calibration.has_value());
}

// Every value the parser refuses: exit 2 and one line naming the program.
void expect_usage_error(std::vector<std::string> words, const std::string& part) {
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  SensorOptions options;
  sim::apps::add_sensor_options(cli, options, SensorKind::camera);
  testing::internal::CaptureStderr();
  words.insert(words.begin(), "sim_test");
  const auto code = parse(cli, words);
  const std::string message = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(code.has_value()) << words[1];
  EXPECT_EQ(*code, sim::apps::kExitUsage);
  EXPECT_EQ(message.rfind("sim_test: ", 0), 0U) << message;
  EXPECT_NE(message.find(part), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), message.size() - 1) << message;
}

TEST(SensorOptions, ABadFrameNameOrANumberThatIsNotFiniteIsAUsageError) {
  expect_usage_error({"--frame-id", "lidar top"}, "--frame-id");
  expect_usage_error({"--parent-frame", "/base_link"}, "--parent-frame");
  expect_usage_error({"--frame-id", "cam\xc3\xa9ra"}, "--frame-id");
  expect_usage_error({"--x", "nan"}, "finite");
  expect_usage_error({"--yaw", "inf"}, "finite");
  expect_usage_error({"--z", "up"}, "--z");
  TempFolder folder;
  expect_usage_error({"--config", folder.file("c.yaml", "roll: .nan\n")}, "roll");
  expect_usage_error({"--config", folder.file("d.yaml", "frame_id: 'a b'\n")}, "frame");
}

TEST(SensorOptions, ABadCalibrationFileIsRefusedWithOneSentence) {
  TempFolder folder;
  SensorOptions options;
  options.camera_info = folder.file("bad.yaml", "image_width: 640\nimage_height: [\n");
  auto malformed = sim::apps::sensor_info_from(options, "/camera");
  ASSERT_FALSE(malformed);
  EXPECT_EQ(malformed.error().code, sim::ErrorCode::invalid_argument);
  EXPECT_NE(malformed.error().message.find("bad.yaml"), std::string::npos);

  options.camera_info = folder.file("missing_dir/none.yaml", "");
  auto missing = sim::apps::sensor_info_from(options, "/camera");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, sim::ErrorCode::invalid_argument);
}

TEST(SensorOptions, ACalibrationOfAnotherSizeIsRefusedWithOneSentence) {
  SensorOptions options;
  options.camera_info = kData + "/camera_front.yaml";
  auto info = sim::apps::sensor_info_from(options, "/camera");
  ASSERT_TRUE(info) << info.error().message;
  auto mismatch = sim::apps::check_calibration_size(*info, 640, 480);
  ASSERT_FALSE(mismatch);
  EXPECT_EQ(mismatch.error().code, sim::ErrorCode::invalid_argument);
  EXPECT_NE(mismatch.error().message.find("768x576"), std::string::npos) << mismatch.error().message;
  EXPECT_NE(mismatch.error().message.find("640x480"), std::string::npos);
  // Binning halves the image the calibration describes.
  info->calibration->binning_x = 2;
  info->calibration->binning_y = 2;
  EXPECT_TRUE(sim::apps::check_calibration_size(*info, 384, 288));
}

}  // namespace
