// SPDX-License-Identifier: Apache-2.0
// Chunk compression (zstd and LZ4 frames, through Debian's libzstd and liblz4) and the CRC-32
// MCAP uses (zlib's polynomial, through zlib).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sim/mcap/format.hpp"

namespace sim::mcap::detail {

std::uint32_t crc32(std::span<const std::byte> data, std::uint32_t crc = 0) noexcept;

// Compresses `in` into `out` (resized to fit). zstd_level only matters for zstd.
void compress(Compression compression, std::span<const std::byte> in, std::vector<std::byte>& out,
              int zstd_level);

// Decompresses exactly out.size() bytes; on failure returns why, as a phrase ("zstd: ...").
std::string decompress(Compression compression, std::span<const std::byte> in,
                       std::span<std::byte> out);

}  // namespace sim::mcap::detail
