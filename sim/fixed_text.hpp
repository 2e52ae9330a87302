// SPDX-License-Identifier: Apache-2.0
// Strings in the region's fixed-width fields (internal): NUL-terminated and NUL-padded.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>

namespace sim::detail {

// Stores `text` cut to N − 1 bytes (callers check lengths first), the rest NUL.
template <std::size_t N>
void put_text(char (&field)[N], const std::string& text) noexcept {
  std::memset(field, 0, N);
  std::memcpy(field, text.data(), std::min(text.size(), N - 1));
}

// The string in a field, or false if it is not NUL-terminated and NUL-padded.
template <std::size_t N>
bool take_text(const char (&field)[N], std::string& out) {
  const void* end = std::memchr(field, '\0', N);
  if (end == nullptr) return false;
  const std::size_t length = static_cast<std::size_t>(static_cast<const char*>(end) - field);
  for (std::size_t i = length; i < N; ++i) {
    if (field[i] != '\0') return false;
  }
  out.assign(field, length);
  return true;
}

}  // namespace sim::detail
