// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_tf_message: the path of every /tf_static message the bridge receives. What it
// accepts must encode again to a message that decodes to the same transforms.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/metadata.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto transforms = sim::ros2::decode_tf_message(std::as_bytes(std::span(data, size)));
  if (!transforms) return 0;
  volatile std::uint64_t sink = 0;
  for (const auto& t : *transforms) {
    sink = sink + sim_fuzz::touch(t.header.frame_id) + sim_fuzz::touch(t.child_frame_id);
  }
  auto again = sim::ros2::encode_tf_message(*transforms);
  if (!again) return 0;  // a frame name longer than this layer writes
  auto back = sim::ros2::decode_tf_message(*again);
  if (!back || back->size() != transforms->size()) __builtin_trap();
  for (std::size_t i = 0; i < back->size(); ++i) {
    if ((*back)[i].child_frame_id != (*transforms)[i].child_frame_id ||
        !((*back)[i].transform == (*transforms)[i].transform)) {
      __builtin_trap();
    }
  }
  return 0;
}
