// SPDX-License-Identifier: Apache-2.0
// The images the test camera (mcap_test_camera) writes, so a test can tell every byte a frame
// must hold from its index alone: each row is a ramp shifted by the frame and row numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "sim/clock_status.hpp"
#include "sim/sensor_info.hpp"

namespace sim::testing {

inline constexpr std::int64_t kTestCameraFirstStamp = 1'700'000'000'000'000'000;
inline constexpr std::int64_t kTestCameraPeriodNs = 33'333'333;

inline std::int64_t test_image_stamp(std::uint64_t index) {
  return kTestCameraFirstStamp + static_cast<std::int64_t>(index) * kTestCameraPeriodNs;
}

inline void fill_test_image(std::span<std::byte> out, std::uint32_t stride, std::uint32_t height,
                            std::uint64_t index) {
  for (std::uint32_t row = 0; row < height; ++row) {
    std::byte* line = out.data() + std::size_t{row} * stride;
    const std::uint32_t shift = static_cast<std::uint32_t>(index * 13 + row * 7);
    for (std::uint32_t x = 0; x < stride; ++x) line[x] = static_cast<std::byte>((x + shift) & 0xff);
  }
}

// Pseudo-random bytes (xorshift64), different for every frame: what no compressor can shrink.
inline void fill_noise(std::span<std::byte> out, std::uint64_t index) {
  std::uint64_t x = 0x9E3779B97F4A7C15ull ^ (index + 1) * 0xBF58476D1CE4E5B9ull;
  std::size_t i = 0;
  for (; i + 8 <= out.size(); i += 8) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    std::memcpy(out.data() + i, &x, 8);
  }
  for (; i < out.size(); ++i) out[i] = static_cast<std::byte>(i);
}

// What the test camera says about itself with --calibrated: a plumb_bob calibration of its size
// and a mounting on base_link, every number distinct so a test sees each one arrive.
inline SensorInfo test_camera_sensor(std::uint32_t width, std::uint32_t height) {
  SensorInfo info;
  info.frame_id = "test_camera_optical";
  info.parent_frame = "base_link";
  info.mounting = Mounting{{1.25, -0.5, 1.75}, {0.0, 0.0, 0.6, 0.8}};
  CameraCalibration c;
  c.width = width;
  c.height = height;
  c.camera_name = "test_camera";
  c.d = {-0.25, 0.125, 0.001, -0.002, 0.03};
  c.k = {410.5, 0, width / 2.0 + 0.5, 0, 411.5, height / 2.0 - 0.5, 0, 0, 1};
  c.p = {405.25, 0, width / 2.0, 0, 0, 406.75, height / 2.0, 0, 0, 0, 1, 0};
  info.calibration = c;
  return info;
}

// The clocks mcap_test_camera --clock sets: `fixed` false before its middle frame (a TAI clock
// 37 s ahead, an error), true from it on (the driver's TAI correction applied, ok). Every field
// is set, so a restored record that lost one differs.
inline ClockStatus test_camera_clock(bool fixed) {
  ClockStatus c;
  c.source = ClockSource::ptp;
  c.state = ClockState::locked;
  c.ptp_domain = 0;
  c.offset_from_master_ns = -42;
  c.path_delay_ns = 1'500;
  c.grandmaster = "00a069.fffe.0b552d";
  c.utc_offset_s = 37;
  c.ptp_timescale = true;
  c.reported_ns = 1'700'000'000'123'456'789;
  c.spread_ns = 3'000;
  c.drift_ppm = 0.1 + 0.2;
  c.steps = 1;
  c.last_step_ns = -1'000;
  c.packets_measured = 4'321;
  c.measured_ns = 1'700'000'000'987'654'321;
  c.tai_correction_ns = fixed ? 37'000'000'000 : 0;
  c.offset_to_host_ns = fixed ? 12'000 : 37'000'012'000;
  c.stamps = fixed ? StampClock::sensor_tai_corrected : StampClock::sensor;
  c.verdict = fixed ? ClockVerdict::ok : ClockVerdict::error;
  c.problem = fixed ? "" : "stamps are 37 s ahead of this host: the sensor serves TAI";
  return c;
}

}  // namespace sim::testing
