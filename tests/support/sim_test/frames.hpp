// SPDX-License-Identifier: Apache-2.0
// Frames whose content proves they are whole (any mix of two frames fails check_frame), and the
// peer's "key=value" output. Unique names and guards: streams.hpp; child processes: process.hpp.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>

#include "sim/reader.hpp"
#include "sim_test/streams.hpp"

namespace sim::test {

// Unique names and stream guards: tests/support/sim_test/streams.hpp, shared by every suite.
using sim::testing::StreamGuard;
using sim::testing::unique_name;

// Frame content derived from the sequence number: any mix of two frames fails check_frame.
inline std::uint64_t pattern_word(std::uint64_t seq, std::uint64_t index) {
  std::uint64_t z = seq * 0x9E3779B97F4A7C15ull + index * 0xBF58476D1CE4E5B9ull + 1;
  z = (z ^ (z >> 31)) * 0x94D049BB133111EBull;
  return z ^ (z >> 29);
}
inline void fill_frame(std::span<std::byte> out, std::uint64_t seq) {
  const std::size_t words = out.size() / 8;
  for (std::size_t i = 0; i < words; ++i) {
    const std::uint64_t w = i == 0 ? seq : pattern_word(seq, i);
    std::memcpy(out.data() + i * 8, &w, 8);
  }
}
// Whole means: the first word names the frame and every word matches that frame's pattern.
inline bool check_frame(std::span<const std::byte> in, std::uint64_t expected_seq) {
  const std::size_t words = in.size() / 8;
  if (words == 0) return false;
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t w;
    std::memcpy(&w, in.data() + i * 8, 8);
    if (w != (i == 0 ? expected_seq : pattern_word(expected_seq, i))) return false;
  }
  return true;
}
// Reads a word of a borrowed frame the writer may be overwriting at this moment. The race is the
// point of the test (still_valid() decides afterwards), so ThreadSanitizer must not flag it.
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
__attribute__((no_sanitize("thread")))
#endif
#endif
#if defined(__SANITIZE_THREAD__)
__attribute__((no_sanitize("thread")))
#endif
inline std::uint64_t racy_word(std::span<const std::byte> in, std::size_t index) {
  const volatile std::uint64_t* p = reinterpret_cast<const volatile std::uint64_t*>(in.data());
  return p[index];
}

// Frame sizes vary with the sequence number so a torn length would show too.
inline std::size_t frame_size(std::uint64_t seq, std::size_t min_bytes, std::size_t max_bytes) {
  const std::size_t span = (max_bytes - min_bytes) / 8;
  return min_bytes + (span == 0 ? 0 : (pattern_word(seq, 0) % (span + 1)) * 8);
}

// Reads "key=value" out of a line of the peer's output.
inline std::uint64_t field(const std::string& line, const std::string& key) {
  const auto at = line.find(key + "=");
  if (at == std::string::npos) return ~0ull;
  return std::stoull(line.substr(at + key.size() + 1));
}

}  // namespace sim::test
