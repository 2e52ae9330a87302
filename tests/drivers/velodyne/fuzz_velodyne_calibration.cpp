// SPDX-License-Identifier: Apache-2.0
// Fuzzes the two calibration readers with outside text: [0] YAML (ros-drivers/velodyne) or
// [1] an HDL-64E db.xml, then the text. A parsed calibration must be usable by an assembler.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sim/velodyne/velodyne.hpp"

using namespace sim::velodyne;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  auto calibration = (data[0] & 1) ? Calibration::parse_db_xml(text) : Calibration::parse_yaml(text);
  if (!calibration) {
    if (calibration.error().message.empty()) __builtin_trap();  // every refusal says why
    return 0;
  }
  for (Model model : all_models) {
    if (info(model).lasers != calibration->lasers()) continue;
    AssemblerOptions options;
    options.model = model;
    (void)FrameAssembler::create(*calibration, options);
  }
  return 0;
}
