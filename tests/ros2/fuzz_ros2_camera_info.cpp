// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_camera_info: the path of every CameraInfo the bridge receives. What it accepts
// must encode again to a message that decodes to the same calibration.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/metadata.hpp"

namespace {

// Field by field: GCC 12 emits no body for CameraCalibration's defaulted operator==.
bool same_calibration(const sim::CameraCalibration& a, const sim::CameraCalibration& b) {
  return a.width == b.width && a.height == b.height && a.distortion_model == b.distortion_model &&
         a.d == b.d && a.k == b.k && a.r == b.r && a.p == b.p && a.binning_x == b.binning_x &&
         a.binning_y == b.binning_y && a.roi.x_offset == b.roi.x_offset &&
         a.roi.y_offset == b.roi.y_offset && a.roi.width == b.roi.width &&
         a.roi.height == b.roi.height && a.roi.do_rectify == b.roi.do_rectify;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto view = sim::ros2::decode_camera_info(std::as_bytes(std::span(data, size)));
  if (!view) return 0;
  volatile std::uint64_t sink = sim_fuzz::touch(view->header.frame_id) +
                                sim_fuzz::touch(view->calibration.distortion_model);
  (void)sink;
  auto again = sim::ros2::encode_camera_info(view->header, view->calibration);
  if (!again) return 0;  // a frame_id or model longer than this layer writes
  auto back = sim::ros2::decode_camera_info(*again);
  if (!back || !same_calibration(back->calibration, view->calibration)) __builtin_trap();
  return 0;
}
