// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary bytes as a sensor's PTC answer, through the header and response
// checks and, when they accept it, the calibration parser and the inventory reader the client
// hands the payload to.
// Input: [command] then the answer. Invariants: no out-of-bounds access (ASan), every refusal
// says why in one line, an accepted payload lies inside the answer.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t command = data[0];
  const std::span<const std::uint8_t> answer(data + 1, size - 1);

  auto header = ptc::parse_header(answer, command);
  if (!header && (header.error().message.empty() ||
                  header.error().message.find('\n') != std::string::npos)) {
    __builtin_trap();
  }
  auto payload = ptc::parse_response(answer, command);
  if (!payload) {
    if (payload.error().message.empty()) __builtin_trap();
    return 0;
  }
  if (!header) __builtin_trap();  // a whole answer has a good header
  if (payload->size() != header->payload_size) __builtin_trap();
  if (payload->data() != answer.data() + ptc::header_size) __builtin_trap();
  const std::string_view text(reinterpret_cast<const char*>(payload->data()), payload->size());
  auto calibration = Calibration::parse(text, std::nullopt, "served calibration");
  if (!calibration && calibration.error().message.empty()) __builtin_trap();
  auto inventory = ptc::parse_inventory(*payload);
  if (!inventory && inventory.error().message.empty()) __builtin_trap();
  if (inventory) {
    // Only printable ASCII reaches a stream's description.
    for (const std::string* field : {&inventory->serial, &inventory->sensor_firmware,
                                     &inventory->control_firmware, &inventory->software}) {
      for (const char c : *field) {
        if (c < 0x20 || c > 0x7E) __builtin_trap();
      }
    }
  }
  return 0;
}
