// SPDX-License-Identifier: Apache-2.0
#include "crc32_mpeg2.hpp"

#include <array>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

namespace sim::hesai::detail {
namespace {

// Established on the real QT128 capture, whose every packet it matches. Two ways: tables on any
// CPU, slicing by 16 (sixteen 1 KiB tables, 16 bytes per step, 16 independent loads per step
// instead of a chain of 16 dependent ones: the 1,071 bytes checked per packet were 12 % of the
// QT128's decode time with slicing by 8), and on x86-64 carry-less multiplication for the
// 1,028-byte body. No CPU has a CRC instruction for this polynomial; an ARM PMULL path would be
// the next step for Jetson-class machines.
constexpr std::size_t crc_slices = 16;
struct CrcTables {
  // t[k][i]: the CRC register after byte i followed by k zero bytes.
  std::array<std::array<std::uint32_t, 256>, crc_slices> t{};
  constexpr CrcTables() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i << 24;
      for (int k = 0; k < 8; ++k) c = (c & 0x8000'0000u) ? (c << 1) ^ 0x04C1'1DB7u : c << 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i) {
      for (std::size_t k = 1; k < crc_slices; ++k) {
        t[k][i] = (t[k - 1][i] << 8) ^ t[0][t[k - 1][i] >> 24];
      }
    }
  }
};
constexpr CrcTables crc_tables{};

// Continues the CRC register `c` over n bytes, table-driven (any CPU).
std::uint32_t crc32_mpeg2_tables(std::uint32_t c, const std::uint8_t* p, std::size_t n) noexcept {
  const auto& t = crc_tables.t;
  for (; n >= crc_slices; n -= crc_slices, p += crc_slices) {
    // The register meets the first four bytes; the other twelve enter through their tables.
    const std::uint32_t hi = c ^ ((std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                                  (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]});
    c = t[15][hi >> 24] ^ t[14][(hi >> 16) & 0xFF] ^ t[13][(hi >> 8) & 0xFF] ^
        t[12][hi & 0xFF] ^ t[11][p[4]] ^ t[10][p[5]] ^ t[9][p[6]] ^ t[8][p[7]] ^ t[7][p[8]] ^
        t[6][p[9]] ^ t[5][p[10]] ^ t[4][p[11]] ^ t[3][p[12]] ^ t[2][p[13]] ^ t[1][p[14]] ^
        t[0][p[15]];
  }
  for (; n > 0; --n, ++p) c = (c << 8) ^ t[0][((c >> 24) ^ *p) & 0xFF];
  return c;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SIM_HESAI_CRC_CLMUL 1
// x^k mod P (P = x^32 + 0x04C11DB7), bit i = coefficient of x^i: the folding constants.
constexpr std::uint64_t x_pow_mod(unsigned k) {
  std::uint64_t r = 1;
  for (unsigned i = 0; i < k; ++i) {
    r <<= 1;
    if (r & (std::uint64_t{1} << 32)) r ^= (std::uint64_t{1} << 32) | 0x04C1'1DB7u;
  }
  return r;
}

// The body CRC (1,028 bytes) by carry-less multiplication (Intel, "Fast CRC computation for
// generic polynomials using PCLMULQDQ", 2009), on x86-64 CPUs that have it (every one since
// 2010; checked at run time, no -march needed). The message is a polynomial, first byte
// highest; the register is kept as 128 bits M congruent to the message so far, and 16 bytes
// D further on become M·x^128 + D = M_hi·(x^192 mod P) + M_lo·(x^128 mod P) + D, which is
// again 128 bits wide. Four such registers run side by side, 64 bytes apart, so the
// multiplications overlap. At the end the 128 bits go through the tables from a zero register,
// which gives (M·x^32) mod P: the CRC register the table code continues from.
#define SIM_HESAI_CLMUL_TARGET __attribute__((target("pclmul,ssse3")))

// 16 bytes, byte order reversed so the 128-bit lane holds them as one big-endian number.
SIM_HESAI_CLMUL_TARGET inline __m128i load_big_endian(const std::uint8_t* at) noexcept {
  const __m128i reverse = _mm_set_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  return _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at)), reverse);
}

// m_hi·k_hi + m_lo·k_lo + d, with k = {x^(b+64) mod P, x^b mod P} to move m on by b bits.
SIM_HESAI_CLMUL_TARGET inline __m128i fold(__m128i m, __m128i k, __m128i d) noexcept {
  return _mm_xor_si128(
      _mm_xor_si128(_mm_clmulepi64_si128(m, k, 0x11), _mm_clmulepi64_si128(m, k, 0x00)), d);
}

SIM_HESAI_CLMUL_TARGET std::uint32_t crc32_mpeg2_clmul(const std::uint8_t* p,
                                                       std::size_t n) noexcept {
  const __m128i k128 = _mm_set_epi64x(static_cast<long long>(x_pow_mod(192)),
                                      static_cast<long long>(x_pow_mod(128)));
  const __m128i k512 = _mm_set_epi64x(static_cast<long long>(x_pow_mod(576)),
                                      static_cast<long long>(x_pow_mod(512)));
  // The initial register value 0xFFFFFFFF is the same as xor-ing it into the first 4 bytes.
  __m128i m0 = _mm_xor_si128(load_big_endian(p), _mm_set_epi32(-1, 0, 0, 0));
  __m128i m1 = load_big_endian(p + 16);
  __m128i m2 = load_big_endian(p + 32);
  __m128i m3 = load_big_endian(p + 48);
  p += 64;
  n -= 64;
  for (; n >= 64; n -= 64, p += 64) {
    m0 = fold(m0, k512, load_big_endian(p));
    m1 = fold(m1, k512, load_big_endian(p + 16));
    m2 = fold(m2, k512, load_big_endian(p + 32));
    m3 = fold(m3, k512, load_big_endian(p + 48));
  }
  __m128i m = fold(fold(fold(m0, k128, m1), k128, m2), k128, m3);
  for (; n >= 16; n -= 16, p += 16) m = fold(m, k128, load_big_endian(p));
  alignas(16) std::uint8_t bytes[16];
  const __m128i reverse = _mm_set_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  _mm_store_si128(reinterpret_cast<__m128i*>(bytes), _mm_shuffle_epi8(m, reverse));
  return crc32_mpeg2_tables(crc32_mpeg2_tables(0, bytes, 16), p, n);
}

bool cpu_has_clmul() noexcept {
  static const bool yes = __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("ssse3");
  return yes;
}
#endif

}  // namespace

std::uint32_t crc32_mpeg2(const std::uint8_t* p, std::size_t n) noexcept {
#ifdef SIM_HESAI_CRC_CLMUL
  if (n >= 64 && cpu_has_clmul()) return crc32_mpeg2_clmul(p, n);
#endif
  return crc32_mpeg2_tables(0xFFFF'FFFFu, p, n);
}

std::uint32_t crc32_mpeg2_portable(const std::uint8_t* p, std::size_t n) noexcept {
  return crc32_mpeg2_tables(0xFFFF'FFFFu, p, n);
}

bool crc32_mpeg2_folds() noexcept {
#ifdef SIM_HESAI_CRC_CLMUL
  return cpu_has_clmul();
#else
  return false;
#endif
}

}  // namespace sim::hesai::detail
