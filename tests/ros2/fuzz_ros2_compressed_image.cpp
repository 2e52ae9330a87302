// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_compressed_image: the path of every CompressedImage the bridge receives.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto view = sim::ros2::decode_compressed_image(std::as_bytes(std::span(data, size)));
  if (!view) return 0;
  volatile std::uint64_t sink = sim_fuzz::touch(view->data) + sim_fuzz::touch(view->format) +
                                sim_fuzz::touch(view->header.frame_id);
  (void)sink;
  return 0;
}
