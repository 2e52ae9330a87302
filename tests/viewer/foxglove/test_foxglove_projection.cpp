// SPDX-License-Identifier: Apache-2.0
// The page's projection of LiDAR points into a camera image, as plain math: poses through chains
// of mountings (up the parent frames to a common one and down), refusals for frames no chain
// joins and for loops, and the pinhole model with distortion, binning and ROI, checked against
// values worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "foxglove_messages.hpp"
#include "projection.hpp"

namespace {

using sim::foxglove::FrameTransform;
using sim::foxglove::Pose;

constexpr double kHalf = 0.70710678118654752;

void expect_near(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 1e-9) << "coordinate " << i;
}

TEST(FoxgloveProjection, APoseGoesUpTheParentFramesAndDownToTheTarget) {
  // lidar on a roof rack turned 90° left, the rack 2 m up on base_link; the camera 1 m ahead.
  const std::vector<FrameTransform> mountings = {
      {"roof_rack", "lidar", sim::Mounting{{0, 0, 0.5}, {0, 0, kHalf, kHalf}}},
      {"base_link", "roof_rack", sim::Mounting{{0, 0, 2.0}, {0, 0, 0, 1}}},
      {"base_link", "camera", sim::Mounting{{1.0, 0, 0}, {0, 0, 0, 1}}},
  };
  auto pose = sim::foxglove::pose_between(mountings, "lidar", "camera");
  ASSERT_TRUE(pose) << pose.error().message;
  // The lidar's +x is the vehicle's +y: (1, 0, 0) in the lidar is (0, 1, 2.5) on base_link,
  // (-1, 1, 2.5) from the camera.
  expect_near(pose->apply({1, 0, 0}), {-1, 1, 2.5});
  expect_near(pose->apply({0, 0, 0}), {-1, 0, 2.5});
  // And back again.
  auto back = sim::foxglove::pose_between(mountings, "camera", "lidar");
  ASSERT_TRUE(back);
  expect_near(back->apply(pose->apply({0.3, -2, 7})), {0.3, -2, 7});
}

TEST(FoxgloveProjection, FramesNoChainJoinsAndLoopsAreRefusedWithASentence) {
  const std::vector<FrameTransform> apart = {
      {"base_link", "camera", sim::Mounting{}},
      {"trailer", "lidar", sim::Mounting{}},
  };
  auto none = sim::foxglove::pose_between(apart, "lidar", "camera");
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("no chain of mountings"), std::string::npos);
  const std::vector<FrameTransform> loop = {
      {"b", "a", sim::Mounting{}},
      {"a", "b", sim::Mounting{}},
  };
  auto looped = sim::foxglove::pose_between(loop, "a", "camera");
  ASSERT_FALSE(looped);
  EXPECT_NE(looped.error().message.find("loop"), std::string::npos);
}

sim::CameraCalibration calibration() {
  sim::CameraCalibration c;
  c.width = 640;
  c.height = 480;
  c.k = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  c.p = {500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0};
  c.d = {0, 0, 0, 0, 0};
  return c;
}

TEST(FoxgloveProjection, APinholeCameraWithPlumbBobDistortionProjectsAsOpenCvDoes) {
  sim::CameraCalibration c = calibration();
  auto centre = sim::foxglove::project_to_pixel(c, 640, 480, {0, 0, 5});
  ASSERT_TRUE(centre);
  EXPECT_FLOAT_EQ((*centre)[0], 320);
  EXPECT_FLOAT_EQ((*centre)[1], 240);
  // x = 0.2, y = 0.1 (normalised); k1 = -0.1, p1 = 0.01: r² = 0.05, radial = 0.995,
  // x' = 0.199 + 2·0.01·0.02 = 0.1994, y' = 0.0995 + 0.01·(0.05 + 0.02) = 0.1002.
  c.d = {-0.1, 0, 0.01, 0, 0};
  auto p = sim::foxglove::project_to_pixel(c, 640, 480, {1, 0.5, 5});
  ASSERT_TRUE(p);
  EXPECT_NEAR((*p)[0], 320 + 500 * 0.1994, 1e-3);
  EXPECT_NEAR((*p)[1], 240 + 500 * 0.1002, 1e-3);
  // Behind the camera, or outside the picture: not drawn.
  EXPECT_FALSE(sim::foxglove::project_to_pixel(c, 640, 480, {0, 0, -5}));
  EXPECT_FALSE(sim::foxglove::project_to_pixel(c, 640, 480, {50, 0, 5}));
}

TEST(FoxgloveProjection, BinningAndRegionOfInterestMoveThePixelAsRosDefinesThem) {
  sim::CameraCalibration c = calibration();
  c.binning_x = 2;
  c.binning_y = 2;
  c.roi.x_offset = 100;
  c.roi.y_offset = 40;
  auto p = sim::foxglove::project_to_pixel(c, 320, 240, {0, 0, 5});
  ASSERT_TRUE(p);
  EXPECT_FLOAT_EQ((*p)[0], (320 - 100) / 2.0f);
  EXPECT_FLOAT_EQ((*p)[1], (240 - 40) / 2.0f);
}

TEST(FoxgloveProjection, AnEquidistantLensBendsByTheAngle) {
  sim::CameraCalibration c = calibration();
  c.distortion_model = "equidistant";
  c.d = {0.1, 0, 0, 0};
  // r = 0.2: theta = atan(0.2), theta_d = theta (1 + 0.1 theta²), x' = 0.2 theta_d / r.
  const double theta = std::atan(0.2);
  const double expected = 320 + 500 * (theta * (1 + 0.1 * theta * theta));
  auto p = sim::foxglove::project_to_pixel(c, 640, 480, {1, 0, 5});
  ASSERT_TRUE(p);
  EXPECT_NEAR((*p)[0], expected, 1e-3);
  EXPECT_NEAR((*p)[1], 240, 1e-3);
}

// Review turn 4 L4: a wide fisheye (1280x960, fx = 330) sees 76 degrees off axis inside its
// picture, where the undistorted pixel (u = 640 + 330 tan 76°, about 1963) is far outside.
TEST(FoxgloveProjection, AWideFisheyeDrawsItsPeriphery) {
  sim::CameraCalibration c;
  c.width = 1280;
  c.height = 960;
  c.distortion_model = "equidistant";
  c.d = {0, 0, 0, 0};
  c.k = {330, 0, 640, 0, 330, 480, 0, 0, 1};
  c.p = {330, 0, 640, 0, 0, 330, 480, 0, 0, 0, 1, 0};
  const double theta = 76.0 * 3.14159265358979323846 / 180.0;
  auto p = sim::foxglove::project_to_pixel(c, 1280, 960, {std::sin(theta), 0, std::cos(theta)});
  ASSERT_TRUE(p) << "a point at 76 degrees off axis was not drawn";
  EXPECT_NEAR((*p)[0], 640 + 330 * theta, 1e-3);
  EXPECT_NEAR((*p)[1], 480, 1e-3);
}

// Review turn 4 L3: Foxglove's CameraCalibration has no binning or ROI, so a 2x-binned, cut
// picture got the full sensor's K, P and size and Foxglove drew overlays at twice the distance
// from the corner. What goes to Foxglove is the picture's own camera: with it, a plain pinhole
// projection puts every point where the full calibration with binning and ROI puts it.
TEST(FoxgloveProjection, TheCalibrationSentToFoxgloveIsThePictureOfABinnedCutCamera) {
  sim::CameraCalibration full = calibration();
  full.d = {0.05, -0.01, 0.001, 0.002, 0};
  full.binning_x = 2;
  full.binning_y = 2;
  full.roi.x_offset = 100;
  full.roi.y_offset = 40;
  full.roi.width = 400;
  full.roi.height = 320;
  const sim::CameraCalibration picture = sim::foxglove::reduced_calibration(full);
  EXPECT_EQ(picture.width, 200u);
  EXPECT_EQ(picture.height, 160u);
  EXPECT_EQ(picture.binning_x, 0u);
  EXPECT_EQ(picture.roi.x_offset, 0u);
  EXPECT_DOUBLE_EQ(picture.k[0], 250);
  EXPECT_DOUBLE_EQ(picture.k[2], (320 - 100) / 2.0);
  EXPECT_DOUBLE_EQ(picture.p[6], (240 - 40) / 2.0);
  for (const std::array<double, 3> point : {std::array<double, 3>{0, 0, 5}, {0.3, 0.1, 4}, {-0.2, -0.1, 3}}) {
    const auto expected = sim::foxglove::project_to_pixel(full, 200, 160, point);
    const auto got = sim::foxglove::project_to_pixel(picture, 200, 160, point);
    ASSERT_TRUE(expected && got) << point[0] << " " << point[1];
    EXPECT_NEAR((*got)[0], (*expected)[0], 1e-3);
    EXPECT_NEAR((*got)[1], (*expected)[1], 1e-3);
  }
  // The message carries the picture's size: after the CDR header, the stamp and "cam\0".
  const auto message = sim::foxglove::encode_calibration(full, "cam", 0);
  ASSERT_GE(message.size(), 28u);
  std::uint32_t width = 0, height = 0;
  std::memcpy(&width, message.data() + 20, 4);
  std::memcpy(&height, message.data() + 24, 4);
  EXPECT_EQ(width, 200u);
  EXPECT_EQ(height, 160u);
  // Neither binning nor ROI: sent as it is.
  EXPECT_EQ(sim::foxglove::reduced_calibration(calibration()), calibration());
}

}  // namespace
