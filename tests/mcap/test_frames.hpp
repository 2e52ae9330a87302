// SPDX-License-Identifier: Apache-2.0
// The images the test camera (mcap_test_camera) writes, so a test can tell every byte a frame
// must hold from its index alone: each row is a ramp shifted by the frame and row numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

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

}  // namespace sim::testing
