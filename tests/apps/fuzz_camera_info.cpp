// SPDX-License-Identifier: Apache-2.0
// The camera calibration parser on any bytes: a calibration or one sentence, never a crash; and
// what it accepts, written out, reads back the same.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "sim/apps/camera_info_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;  // load_camera_info refuses large files before parsing
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto calibration = sim::apps::parse_camera_info(text);
  if (!calibration) {
    if (calibration.error().message.empty()) std::abort();
    return 0;
  }
  auto again = sim::apps::parse_camera_info(sim::apps::format_camera_info(*calibration));
  if (!again || !(*again == *calibration)) std::abort();
  return 0;
}
