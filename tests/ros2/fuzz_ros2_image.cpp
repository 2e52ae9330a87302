// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_image + sim_image_layout: the path of every Image the bridge receives.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto view = sim::ros2::decode_image(std::as_bytes(std::span(data, size)));
  if (!view) return 0;
  volatile std::uint64_t sink = sim_fuzz::touch(view->data) + sim_fuzz::touch(view->encoding) +
                                sim_fuzz::touch(view->header.frame_id);
  auto layout = sim::ros2::sim_image_layout(*view);
  if (layout && layout->frame_bytes() != view->data.size()) __builtin_trap();
  (void)sink;
  return 0;
}
