// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the metadata JSON parser (FW 2.x flat and 3.x nested). A metadata it accepts
// must be self-consistent enough for the frame assembler to be built from it.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sim/ouster/ouster.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto metadata = sim::ouster::Metadata::parse(text);
  if (!metadata) return 0;
  if (metadata->beam_altitude_deg.size() != metadata->beams()) __builtin_trap();
  if (metadata->pixel_shift_by_row.size() != metadata->beams()) __builtin_trap();
  (void)metadata->describe();
  (void)metadata->window_columns();
  // Small ones only: a 128 × 4096 lookup table per input would slow the fuzzer to a crawl.
  if (std::size_t{metadata->beams()} * metadata->columns() <= 64 * 1024) {
    auto assembler = sim::ouster::FrameAssembler::create(*metadata, {});
    if (!assembler) __builtin_trap();
  }
  return 0;
}
