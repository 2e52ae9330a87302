// SPDX-License-Identifier: Apache-2.0
// CRC-32/MPEG-2 (polynomial 0x04C11DB7, not reflected, initial value 0xFFFFFFFF, no final xor):
// the CRC of the PandarQT128's body, functional-safety and tail sections. Internal to the
// decoder; the two implementations are declared so the tests can hold them to each other.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sim::hesai::detail {

// The CRC of n bytes, by the fastest way this CPU has.
std::uint32_t crc32_mpeg2(const std::uint8_t* p, std::size_t n) noexcept;
// The same by tables, on any CPU (what aarch64 always runs).
std::uint32_t crc32_mpeg2_portable(const std::uint8_t* p, std::size_t n) noexcept;
// Whether crc32_mpeg2 folds by carry-less multiplication here (x86-64 with PCLMULQDQ).
bool crc32_mpeg2_folds() noexcept;

}  // namespace sim::hesai::detail
