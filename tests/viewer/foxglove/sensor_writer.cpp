// SPDX-License-Identifier: Apache-2.0
// A test writer of one calibrated camera and one LiDAR, both mounted on base_link, with a
// scene whose picture is known: the camera sees a flat grey image; the LiDAR sees a wall of
// points 5 m ahead of the vehicle (and the same wall 5 m behind it, which no camera looking
// forward may show). The sensor descriptions are set with StreamSpec::sensor directly, so the
// Foxglove tests do not depend on any driver's options.
//
//   camera  frame test_camera_optical, 1.5 m up, looking forward (the optical frame: x right,
//           y down, z forward); 320x240, fx = fy = 200, cx = 160, cy = 120, no distortion
//   lidar   frame test_lidar, 2 m up, turned 90° left (its x axis points to the vehicle's left)
//   wall    x = 5 m, y from -1 to 1 m, z from 0.5 to 2.5 m in base_link, which the camera sees at
//           u = 120..200, v = 80..160
//
// Usage: sensor_writer CAMERA LIDAR [RECALIBRATE_AT_FRAME]. Prints "ready" once both streams
// exist; runs until killed. At frame RECALIBRATE_AT_FRAME (if given) the camera is recalibrated
// (cx = 170) through Writer::set_sensor_info and "recalibrated" is printed.
//
// Clocks (Writer::set_clock): the camera's PTP clock is still acquiring (verdict warn, with the
// problem sentence of harness.mjs's scene.cameraClockProblem); the LiDAR's is locked (ok).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/sim.hpp"

namespace {

constexpr std::uint32_t kWidth = 320, kHeight = 240;

sim::SensorInfo camera_sensor(double cx) {
  sim::SensorInfo info;
  info.frame_id = "test_camera_optical";
  info.parent_frame = "base_link";
  info.mounting = sim::Mounting{{0.0, 0.0, 1.5}, {-0.5, 0.5, -0.5, 0.5}};
  sim::CameraCalibration c;
  c.width = kWidth;
  c.height = kHeight;
  c.camera_name = "test_camera";
  c.distortion_model = "plumb_bob";
  c.d = {0, 0, 0, 0, 0};
  c.k = {200, 0, cx, 0, 200, 120, 0, 0, 1};
  c.p = {200, 0, cx, 0, 0, 200, 120, 0, 0, 0, 1, 0};
  info.calibration = c;
  info.calibration_source = "tests/viewer/foxglove/sensor_writer.cpp";
  info.time_base = sim::TimeBase::host;
  return info;
}

sim::ClockStatus camera_clock() {
  sim::ClockStatus c;
  c.source = sim::ClockSource::ptp;
  c.state = sim::ClockState::acquiring;
  c.ptp_domain = 0;
  c.offset_from_master_ns = 250'000;
  c.grandmaster = "00a069.fffe.0b552d";
  c.offset_to_host_ns = 300'000;
  c.spread_ns = 20'000;
  c.verdict = sim::ClockVerdict::warn;
  c.problem = "the camera's PTP clock is still acquiring; wait until ptp4l reports it locked";
  c.stamps = sim::StampClock::sensor;
  return c;
}

sim::ClockStatus lidar_clock() {
  sim::ClockStatus c;
  c.source = sim::ClockSource::ptp;
  c.state = sim::ClockState::locked;
  c.ptp_domain = 0;
  c.offset_from_master_ns = -42;
  c.grandmaster = "00a069.fffe.0b552d";
  c.offset_to_host_ns = 12'000;
  c.spread_ns = 3'000;
  c.verdict = sim::ClockVerdict::ok;
  c.stamps = sim::StampClock::sensor;
  return c;
}

sim::SensorInfo lidar_sensor() {
  sim::SensorInfo info;
  info.frame_id = "test_lidar";
  info.parent_frame = "base_link";
  info.mounting = sim::Mounting{{0.0, 0.0, 2.0}, {0.0, 0.0, 0.70710678118654752, 0.70710678118654752}};
  info.time_base = sim::TimeBase::host;
  info.point_time = sim::PointTime::after_frame_stamp;
  return info;
}

// The wall ahead and its mirror behind, in the LiDAR's frame: p_lidar = (y, -x, z - 2).
std::vector<sim::LidarPoint> scene() {
  std::vector<sim::LidarPoint> points;
  for (const double x : {5.0, -5.0}) {
    for (int i = 0; i <= 40; ++i) {
      for (int j = 0; j <= 40; ++j) {
        const double y = -1.0 + 0.05 * i, z = 0.5 + 0.05 * j;
        sim::LidarPoint p{};
        p.x = static_cast<float>(y);
        p.y = static_cast<float>(-x);
        p.z = static_cast<float>(z - 2.0);
        p.intensity = 100;
        p.ring = static_cast<std::uint16_t>(j);
        points.push_back(p);
      }
    }
  }
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: sensor_writer CAMERA LIDAR [RECALIBRATE_AT_FRAME]\n");
    return 2;
  }
  const long recalibrate_at = argc > 3 ? std::atol(argv[3]) : -1;
  auto camera = sim::Writer::create(
      {.name = argv[1],
       .layout = sim::Layout::of(sim::ImageLayout::packed(kWidth, kHeight, sim::PixelFormat::bgr8)),
       .sensor = camera_sensor(160)});
  if (!camera) {
    std::fprintf(stderr, "sensor_writer: %s\n", camera.error().message.c_str());
    return 1;
  }
  const std::vector<sim::LidarPoint> points = scene();
  auto lidar = sim::Writer::create(
      {.name = argv[2],
       .layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, points.size())),
       .sensor = lidar_sensor()});
  if (!lidar) {
    std::fprintf(stderr, "sensor_writer: %s\n", lidar.error().message.c_str());
    return 1;
  }
  if (!camera->set_clock(camera_clock()) || !lidar->set_clock(lidar_clock())) {
    std::fprintf(stderr, "sensor_writer: a clock record was refused\n");
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);
  const std::vector<std::byte> image(std::size_t{kWidth} * kHeight * 3, std::byte{50});
  for (long frame = 0;; ++frame) {
    if (frame == recalibrate_at) {
      if (auto done = camera->set_sensor_info(camera_sensor(170)); !done) {
        std::fprintf(stderr, "sensor_writer: %s\n", done.error().message.c_str());
        return 1;
      }
      std::printf("recalibrated\n");
      std::fflush(stdout);
    }
    const std::int64_t now = sim::realtime_ns();
    if (camera->write(image, now) != sim::WriteStatus::ok ||
        lidar->write(std::as_bytes(std::span(points)), now) != sim::WriteStatus::ok) {
      std::fprintf(stderr, "sensor_writer: a frame was not published\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}
