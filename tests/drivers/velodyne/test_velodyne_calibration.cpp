// SPDX-License-Identifier: Apache-2.0
// The calibration readers: every nominal table SIM installs, an HDL-64E db.xml read as the ROS
// driver's gen_calibration.py converts it, and bad files refused with one sentence.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sim/velodyne/velodyne.hpp"

namespace {

using namespace sim::velodyne;

std::filesystem::path shipped(const std::string& name) {
  return std::filesystem::path(VELODYNE_CALIBRATION_DIR) / name;
}

TEST(VelodyneCalibration, EveryShippedNominalTableLoadsWithItsModelsLaserCount) {
  const std::pair<const char*, Model> files[] = {
      {"VLP16.yaml", Model::vlp16}, {"VLP16_hires.yaml", Model::puck_hires}, {"VLP32.yaml", Model::vlp32c},
      {"HDL32.yaml", Model::hdl32e}, {"VLS128.yaml", Model::vls128},         {"HDL64e_s2.yaml", Model::hdl64e},
      {"HDL64e_s3.yaml", Model::hdl64e}};
  for (const auto& [file, model] : files) {
    auto c = Calibration::load(shipped(file));
    ASSERT_TRUE(c) << file << ": " << c.error().message;
    EXPECT_EQ(c->lasers(), info(model).lasers) << file;
    AssemblerOptions o;
    o.model = model;
    EXPECT_TRUE(FrameAssembler::create(*c, o)) << file;
  }
}

TEST(VelodyneCalibration, Vlp16TableHasTheManualsElevationsAndRingsByElevation) {
  auto c = Calibration::load(shipped("VLP16.yaml"));
  ASSERT_TRUE(c);
  // VLP-16 manual: laser 0 at −15°, laser 1 at +1°, … laser 15 at +15°.
  EXPECT_NEAR((*c)[0].vert_correction * 180 / M_PI, -15.0, 1e-9);
  EXPECT_NEAR((*c)[1].vert_correction * 180 / M_PI, 1.0, 1e-9);
  EXPECT_NEAR((*c)[15].vert_correction * 180 / M_PI, 15.0, 1e-9);
  EXPECT_EQ(c->ring(0), 0);   // the lowest beam
  EXPECT_EQ(c->ring(15), 15);
  EXPECT_EQ(c->ring(1), 8);
  EXPECT_DOUBLE_EQ(c->file_distance_resolution_m(), 0.002);
}

TEST(VelodyneCalibration, Hdl64eDbXmlIsReadInRadiansAndMetres) {
  auto c = Calibration::load(std::filesystem::path(VELODYNE_TEST_DATA) / "hdl64e_synthetic.db.xml");
  ASSERT_TRUE(c) << c.error().message;
  ASSERT_EQ(c->lasers(), 64U);
  const LaserCorrection& l0 = (*c)[0];
  EXPECT_NEAR(l0.rot_correction, 2.5 * M_PI / 180, 1e-9);  // degrees → radians
  EXPECT_NEAR(l0.vert_correction, 2.0 * M_PI / 180, 1e-9);
  EXPECT_NEAR(l0.dist_correction, 1.10, 1e-9);              // centimetres → metres
  EXPECT_NEAR(l0.dist_correction_x, 1.15, 1e-9);
  EXPECT_NEAR(l0.vert_offset_correction, 0.215, 1e-9);
  EXPECT_NEAR(l0.horiz_offset_correction, 0.026, 1e-9);
  EXPECT_NEAR(l0.focal_distance, 15.0, 1e-9);
  EXPECT_NEAR(l0.focal_slope, 0.5, 1e-9);
  EXPECT_EQ(l0.min_intensity, 10);
  EXPECT_EQ(l0.max_intensity, 230);
  EXPECT_TRUE(l0.two_point());
  EXPECT_DOUBLE_EQ(c->file_distance_resolution_m(), 0.002);
}

TEST(VelodyneCalibration, BlockAndFlowStyleYamlReadTheSame) {
  auto flow = Calibration::parse_yaml(
      "lasers:\n- {laser_id: 1, vert_correction: 0.1, rot_correction: -0.02}\n"
      "- {laser_id: 0, vert_correction: -0.1}\nnum_lasers: 2\n");
  auto block = Calibration::parse_yaml(
      "num_lasers: 2\nlasers:\n  - laser_id: 0\n    vert_correction: -0.1   # lowest\n"
      "  - laser_id: 1\n    rot_correction: -0.02\n    vert_correction: 0.1\n");
  ASSERT_TRUE(flow) << flow.error().message;
  ASSERT_TRUE(block) << block.error().message;
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ((*flow)[i].vert_correction, (*block)[i].vert_correction);
    EXPECT_EQ((*flow)[i].rot_correction, (*block)[i].rot_correction);
  }
  EXPECT_EQ((*flow)[1].rot_correction, -0.02);
}

TEST(VelodyneCalibration, BadFilesAreRefusedWithOneSentenceNamingTheLine) {
  const struct {
    const char* text;
    const char* says;
  } cases[] = {
      {"lasers:\n- {laser_id: 0, vert_correction: abc}\n", "t.yaml:2: vert_correction 'abc' is not a number."},
      {"lasers:\n- {laser_id: 0}\n- {laser_id: 0}\n", "appears twice"},
      {"lasers:\n- {vert_correction: 0.1}\n", "without laser_id"},
      {"num_lasers: 3\nlasers:\n- {laser_id: 0}\n", "says num_lasers 3 but lists 1"},
      {"hello: world\n", "lists no lasers"},
      {"lasers:\n- {laser_id: 0, vert_correction: 12}\n", "radians expected"},
  };
  for (const auto& c : cases) {
    auto parsed = Calibration::parse_yaml(c.text, "t.yaml");
    ASSERT_FALSE(parsed) << c.text;
    EXPECT_NE(parsed.error().message.find(c.says), std::string::npos) << parsed.error().message;
    EXPECT_EQ(parsed.error().message.back(), '.');
  }
  auto xml = Calibration::parse_db_xml("<DB><points_><item><px><id_>0</id_><rotCorrection_>x</rotCorrection_></px></item></points_></DB>");
  ASSERT_FALSE(xml);
  EXPECT_NE(xml.error().message.find("rotCorrection_ 'x', not a number"), std::string::npos) << xml.error().message;
  EXPECT_FALSE(Calibration::parse_db_xml("not xml at all"));
  EXPECT_FALSE(Calibration::load("/nonexistent/VLP16.yaml"));
}

TEST(VelodyneCalibration, ACalibrationOfAnotherLaserCountIsRefusedBeforeAnyPacket) {
  auto c = Calibration::load(shipped("VLP16.yaml"));
  ASSERT_TRUE(c);
  AssemblerOptions o;
  o.model = Model::vls128;
  auto a = FrameAssembler::create(*c, o);
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().message,
            "the calibration has 16 lasers but a VLS-128 has 128; give the file of this sensor (--calibration).");
}

}  // namespace
