// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary bytes as a sensor's /api/v1/time answer, into a ClockStatus.
// Invariants: no crash or out-of-bounds access (ASan), a refusal is one line, the grandmaster is
// empty or "xxxxxx.xxxx.xxxxxx" in lower-case hex, the domain -1 or a byte, a UTC offset within
// ±1000 s.
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "sim/ouster/time_status.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto clock = sim::ouster::clock_status_from_time_json(text);
  if (!clock) {
    if (clock.error().message.empty() || clock.error().message.find('\n') != std::string::npos) __builtin_trap();
    return 0;
  }
  const std::string& gm = clock->grandmaster;
  if (!gm.empty()) {
    if (gm.size() != 18 || gm[6] != '.' || gm[11] != '.') __builtin_trap();
    for (std::size_t i = 0; i < gm.size(); ++i) {
      if (i == 6 || i == 11) continue;
      if (std::isxdigit(static_cast<unsigned char>(gm[i])) == 0 || std::isupper(static_cast<unsigned char>(gm[i])) != 0) {
        __builtin_trap();
      }
    }
  }
  if (clock->ptp_domain < -1 || clock->ptp_domain > 255) __builtin_trap();
  if (clock->utc_offset_s && (*clock->utc_offset_s < -1000 || *clock->utc_offset_s > 1000)) __builtin_trap();
  return 0;
}
