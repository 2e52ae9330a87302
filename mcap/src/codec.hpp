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
// The CRC of A followed by B from crc32(A), crc32(B) and B's length, without reading B again.
std::uint32_t crc32_combine(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t length_b) noexcept;

// Compresses `in` (not Compression::none) into the start of `out` and returns the compressed
// size. `out` only ever grows: a recorder compresses a chunk of megabytes many times a second,
// and shrinking it after each chunk would make the next one zero-fill megabytes again.
std::size_t compress(Compression compression, std::span<const std::byte> in,
                     std::vector<std::byte>& out, int zstd_level);

// Decompresses exactly out.size() bytes; on failure returns why, as a phrase ("zstd: ...").
std::string decompress(Compression compression, std::span<const std::byte> in,
                       std::span<std::byte> out);

}  // namespace sim::mcap::detail
