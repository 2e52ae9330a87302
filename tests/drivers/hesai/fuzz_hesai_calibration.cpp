// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary text through the angle-correction and firing-time CSV parsers,
// and an assembler built from whatever they accept. Input: [model selector] then the text.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  std::optional<Model> model;
  if (data[0] % 8 < all_models.size()) model = all_models[data[0] % 8];
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);

  auto calibration = Calibration::parse(text, model, "fuzz.csv");
  if (calibration) {
    if (calibration->channels() == 0) __builtin_trap();
    if (model && calibration->channels() != info(*model).channels) __builtin_trap();
    AssemblerOptions options;
    options.model = model.value_or(Model::pandar64);
    (void)FrameAssembler::create(*calibration, options);
  } else if (calibration.error().message.empty()) {
    __builtin_trap();  // every refusal says why
  }
  auto firetimes = FiretimeCorrection::parse(text, model, "fuzz.csv");
  if (!firetimes && firetimes.error().message.empty()) __builtin_trap();
  return 0;
}
