// SPDX-License-Identifier: Apache-2.0
// What sim_foxglove makes of the streams' sensor descriptions, with real SIM streams and the
// library's own parts in this process (review turn 4, L5 and L10): which mounting the transforms
// carry when two streams mount one frame differently, and a projection picture drawn anew when
// only the calibration changed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "catalog.hpp"
#include "page_api.hpp"
#include "page_frames.hpp"
#include "sim/sim.hpp"

namespace {

std::string unique(const std::string& what) {
  return "/fox_desc_" + std::to_string(::getpid()) + "_" + what;
}

// A writer whose region is removed when the test ends, however it ends.
struct Stream {
  explicit Stream(const sim::StreamSpec& spec) : name(spec.name) {
    (void)sim::destroy(name);
    auto created = sim::Writer::create(spec);
    if (!created) ADD_FAILURE() << name << ": " << created.error().message;
    else writer.emplace(std::move(*created));
  }
  ~Stream() {
    writer.reset();
    (void)sim::destroy(name);
  }
  std::string name;
  std::optional<sim::Writer> writer;
};

sim::StreamSpec camera_spec(const std::string& name, const std::optional<sim::SensorInfo>& sensor) {
  sim::StreamSpec spec;
  spec.name = name;
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(64, 48, sim::PixelFormat::mono8));
  spec.sensor = sensor;
  return spec;
}

sim::SensorInfo mounted(const std::string& frame, double x) {
  sim::SensorInfo s;
  s.frame_id = frame;
  s.parent_frame = "base_link";
  s.mounting = sim::Mounting{{x, 0, 0}, {0, 0, 0, 1}};
  return s;
}

// Review L10: the transforms kept the first stream's mounting of a frame (by name) and dropped
// the other without a word, while sim_dds_bridge's /tf_static sends both and tf2 keeps the last.
TEST(FoxgloveDescriptions, TwoStreamsMountingOneFrameDifferentlyAreToldAndTheLaterNameWins) {
  const std::string frame = "desc_cam_" + std::to_string(::getpid()) + "_optical";
  Stream a(camera_spec(unique("a_raw"), mounted(frame, 1.0)));
  Stream b(camera_spec(unique("b_jpeg"), mounted(frame, 2.0)));
  Stream c(camera_spec(unique("c_same"), mounted("desc_other", 3.0)));
  Stream d(camera_spec(unique("d_same"), mounted("desc_other", 3.0)));
  sim::foxglove::Catalog catalog({a.name, b.name, c.name, d.name}, {}, std::chrono::milliseconds(500), {});
  catalog.poll();

  const auto mountings = catalog.mountings();
  ASSERT_EQ(mountings.size(), 2u);
  for (const auto& m : mountings) {
    const double expected_x = m.child == frame ? 2.0 : 3.0;  // the later name's mounting is kept
    EXPECT_EQ(m.mounting.translation[0], expected_x) << m.child;
  }
  const std::string expected = "streams " + a.name + " and " + b.name + " both mount frame " + frame +
                               ", differently; " + b.name + "'s mounting is used";
  for (const auto& name : {a.name, b.name}) {
    const auto entry = catalog.find(name);
    ASSERT_TRUE(entry);
    EXPECT_NE(entry->mounting_problem.find(expected), std::string::npos) << entry->mounting_problem;
  }
  for (const auto& name : {c.name, d.name}) {  // the same mounting twice is no conflict
    EXPECT_EQ(catalog.find(name)->mounting_problem, "");
  }
  // The page's stream table shows it on both.
  const std::string json = sim::foxglove::streams_json(catalog.snapshot(), mountings);
  EXPECT_NE(json.find(expected), std::string::npos) << json;

  // Once the streams agree, nothing is said any more.
  ASSERT_TRUE(b.writer->set_sensor_info(mounted(frame, 1.0)));
  catalog.poll();
  EXPECT_EQ(catalog.find(a.name)->mounting_problem, "");
  EXPECT_EQ(catalog.find(b.name)->mounting_problem, "");
}

// Review L5: the projection picture was cached on the frames, the pose and K's fx and cx only,
// so a recalibration of a paused stream (d, fy, cy, binning, ROI) kept the old overlay.
TEST(FoxgloveDescriptions, AProjectionIsDrawnAnewWhenOnlyTheCalibrationChanged) {
  Stream camera(camera_spec(unique("proj_cam"), std::nullopt));
  sim::StreamSpec lidar_spec;
  lidar_spec.name = unique("proj_lidar");
  lidar_spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 16));
  Stream lidar(lidar_spec);
  ASSERT_TRUE(camera.writer && lidar.writer);
  std::vector<std::byte> pixels(64 * 48, std::byte{40});
  ASSERT_EQ(camera.writer->write(std::span<const std::byte>(pixels), 1), sim::WriteStatus::ok);
  const std::array<float, 12> points = {0, 0, 5, 0.5f, 0.2f, 5, -0.5f, -0.2f, 4, 0.1f, 0.3f, 6};
  ASSERT_EQ(lidar.writer->write(std::span<const float>(points), 1), sim::WriteStatus::ok);

  sim::CameraCalibration c;
  c.width = 64;
  c.height = 48;
  c.k = {50, 0, 32, 0, 50, 24, 0, 0, 1};
  c.p = {50, 0, 32, 0, 0, 50, 24, 0, 0, 0, 1, 0};
  c.d = {0, 0, 0, 0, 0};
  sim::foxglove::PageFrames frames(80, sim::Trust{});
  const sim::foxglove::Pose pose;
  auto first = frames.projection(camera.name, lidar.name, pose, c);
  ASSERT_TRUE(first) << first.error().message;
  auto again = frames.projection(camera.name, lidar.name, pose, c);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->jpeg, first->jpeg) << "the same frames, pose and calibration are not drawn twice";
  for (auto change : {+[](sim::CameraCalibration& k) { k.k[5] = 10; },   // cy
                      +[](sim::CameraCalibration& k) { k.k[4] = 80; },   // fy
                      +[](sim::CameraCalibration& k) { k.d[0] = 0.3; },  // distortion
                      +[](sim::CameraCalibration& k) { k.binning_x = 2; }}) {
    sim::CameraCalibration changed = c;
    change(changed);
    auto redrawn = frames.projection(camera.name, lidar.name, pose, changed);
    ASSERT_TRUE(redrawn) << redrawn.error().message;
    EXPECT_NE(redrawn->jpeg, first->jpeg) << "a changed calibration served the old picture";
    first = redrawn;
  }
}

}  // namespace
