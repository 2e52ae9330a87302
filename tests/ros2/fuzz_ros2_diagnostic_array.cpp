// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_diagnostic_array and clock_from_diagnostic: the path of every /diagnostics message
// sim_play reads from a recording. What it accepts must encode again to the same statuses.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_ros2_decode.hpp"
#include "sim/ros2/diagnostics.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto array = sim::ros2::decode_diagnostic_array(std::as_bytes(std::span(data, size)));
  if (!array) return 0;
  volatile std::uint64_t sink = 0;
  for (const auto& s : array->status) {
    sink = sink + sim_fuzz::touch(s.name) + sim_fuzz::touch(s.message);
    auto clock = sim::ros2::clock_from_diagnostic(s);
    if (clock) sink = sink + clock->steps + sim::clock_status_problem(*clock).size();
  }
  auto again = sim::ros2::encode_diagnostic_array(*array);
  if (!again) return 0;  // a text longer than this layer sends
  auto back = sim::ros2::decode_diagnostic_array(*again);
  if (!back || back->status != array->status) __builtin_trap();
  return 0;
}
