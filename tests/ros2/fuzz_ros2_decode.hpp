// SPDX-License-Identifier: Apache-2.0
// What every ROS 2 decoder fuzz target does with a view it accepted: touch every byte it points
// at (so ASan sees any out-of-bounds view) and run the conversions a subscriber runs next.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace sim_fuzz {

inline std::uint64_t touch(std::span<const std::byte> bytes) {
  std::uint64_t sum = 0;
  for (std::byte b : bytes) sum += std::to_integer<std::uint64_t>(b);
  return sum;
}
inline std::uint64_t touch(std::string_view s) {
  return touch(std::as_bytes(std::span(s.data(), s.size())));
}

}  // namespace sim_fuzz
