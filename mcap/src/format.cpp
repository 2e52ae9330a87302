// SPDX-License-Identifier: Apache-2.0
#include "sim/mcap/format.hpp"

namespace sim::mcap {

std::string_view to_string(Compression compression) noexcept {
  switch (compression) {
    case Compression::none: return "";
    case Compression::lz4: return "lz4";
    case Compression::zstd: return "zstd";
  }
  return "";
}

std::optional<Compression> parse_compression(std::string_view name) noexcept {
  if (name.empty() || name == "none") return Compression::none;
  if (name == "lz4") return Compression::lz4;
  if (name == "zstd") return Compression::zstd;
  return std::nullopt;
}

namespace {

// Length of the UTF-8 sequence starting at text[i] (2–4 bytes), or 0 when it is not one.
std::size_t utf8_sequence(std::string_view text, std::size_t i) {
  const auto lead = static_cast<unsigned char>(text[i]);
  const std::size_t length = lead >= 0xf0 && lead <= 0xf4 ? 4 : lead >= 0xe0 ? 3 : lead >= 0xc2 ? 2 : 0;
  if (length == 0 || lead > 0xf4 || i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((static_cast<unsigned char>(text[i + k]) & 0xc0) != 0x80) return 0;
  }
  const auto second = static_cast<unsigned char>(text[i + 1]);
  if (lead == 0xc2 && second < 0xa0) return 0;                  // C1 controls (U+0080–U+009F)
  if (lead == 0xe0 && second < 0xa0) return 0;                  // overlong
  if (lead == 0xed && second >= 0xa0) return 0;                 // surrogates
  if (lead == 0xf0 && second < 0x90) return 0;                  // overlong
  if (lead == 0xf4 && second >= 0x90) return 0;                 // beyond U+10FFFF
  return length;
}

}  // namespace

std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
      ++i;
    } else if (const std::size_t n = c >= 0x80 ? utf8_sequence(text, i) : 0; n > 0) {
      out.append(text.substr(i, n));
      i += n;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
      ++i;
    }
  }
  return out;
}

}  // namespace sim::mcap
