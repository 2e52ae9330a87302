// SPDX-License-Identifier: Apache-2.0
// SHA-256 (FIPS 180-4) of a byte string, for the RIHS01 type hashes; nothing on a hot path.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace sim::ros2 {

std::array<std::uint8_t, 32> sha256(std::string_view bytes) noexcept;

}  // namespace sim::ros2
