// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_point_cloud2, sim_point_layout and repack_points: the path of every PointCloud2
// the bridge receives.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto view = sim::ros2::decode_point_cloud2(std::as_bytes(std::span(data, size)));
  if (!view) return 0;
  volatile std::uint64_t sink = sim_fuzz::touch(view->data) + sim_fuzz::touch(view->header.frame_id);
  for (const auto& field : view->fields()) sink = sink + sim_fuzz::touch(field.name);
  auto layout = sim::ros2::sim_point_layout(*view);
  if (layout && layout->frame_bytes() != view->data.size()) __builtin_trap();
  std::vector<std::byte> out(24 * 64);  // repack at most 64 points: bounded work per input
  for (auto type : {sim::PointType::xyz32, sim::PointType::lidar_point}) {
    auto n = sim::ros2::repack_points(*view, type, out);
    if (n && *n > out.size() / sim::point_size(type)) __builtin_trap();
  }
  (void)sink;
  return 0;
}
