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

}  // namespace sim::mcap
