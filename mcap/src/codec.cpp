// SPDX-License-Identifier: Apache-2.0
#include "codec.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <stdexcept>

namespace sim::mcap::detail {

std::uint32_t crc32(std::span<const std::byte> data, std::uint32_t crc) noexcept {
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(data.data()), data.size()));
}

std::uint32_t crc32_combine(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t length_b) noexcept {
  return static_cast<std::uint32_t>(
      ::crc32_combine64(crc_a, crc_b, static_cast<z_off64_t>(length_b)));
}

std::size_t compress(Compression compression, std::span<const std::byte> in,
                     std::vector<std::byte>& out, int zstd_level) {
  auto room_for = [&out](std::size_t bound) {
    if (out.size() < bound) out.resize(bound);
  };
  switch (compression) {
    case Compression::none:
      break;
    case Compression::zstd: {
      room_for(ZSTD_compressBound(in.size()));
      const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), zstd_level);
      if (ZSTD_isError(n)) throw std::runtime_error(ZSTD_getErrorName(n));
      return n;
    }
    case Compression::lz4: {
      LZ4F_preferences_t prefs{};
      prefs.frameInfo.contentSize = in.size();
      prefs.frameInfo.blockSizeID = LZ4F_max4MB;
      room_for(LZ4F_compressFrameBound(in.size(), &prefs));
      const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
      if (LZ4F_isError(n)) throw std::runtime_error(LZ4F_getErrorName(n));
      return n;
    }
  }
  throw std::runtime_error("no compression was asked for");
}

std::string decompress(Compression compression, std::span<const std::byte> in,
                       std::span<std::byte> out) {
  switch (compression) {
    case Compression::none:
      if (in.size() != out.size()) return "its stored size differs from its uncompressed size";
      std::copy(in.begin(), in.end(), out.begin());
      return {};
    case Compression::zstd: {
      const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
      if (ZSTD_isError(n)) return std::string("zstd says ") + ZSTD_getErrorName(n);
      if (n != out.size()) return "it decompresses to fewer bytes than it declares";
      return {};
    }
    case Compression::lz4: {
      LZ4F_dctx* ctx = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) return "lz4 has no memory";
      std::size_t done_in = 0;
      std::size_t done_out = 0;
      std::string why;
      while (done_in < in.size() && done_out < out.size()) {
        std::size_t in_n = in.size() - done_in;
        std::size_t out_n = out.size() - done_out;
        const std::size_t hint =
            LZ4F_decompress(ctx, out.data() + done_out, &out_n, in.data() + done_in, &in_n, nullptr);
        if (LZ4F_isError(hint)) {
          why = std::string("lz4 says ") + LZ4F_getErrorName(hint);
          break;
        }
        if (in_n == 0 && out_n == 0) break;  // no progress: truncated input
        done_in += in_n;
        done_out += out_n;
        if (hint == 0) break;  // end of frame
      }
      LZ4F_freeDecompressionContext(ctx);
      if (why.empty() && done_out != out.size()) why = "it decompresses to fewer bytes than it declares";
      return why;
    }
  }
  return "unknown compression";
}

}  // namespace sim::mcap::detail
