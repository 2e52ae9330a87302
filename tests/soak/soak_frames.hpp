// SPDX-License-Identifier: Apache-2.0
// The soak's verifiable frames. A frame written by the soak writer, or a frame of the generated
// video the real sim_replay_video plays, is:
//
//   word 0      kMagic ("SIMSOAK1")
//   word 1      tag: the writer's sequence number (soak writer) or kVideoTag | picture index
//   word 2      how many publish times follow (soak writer: up to kHistory; video: 0)
//   words 3–10  the monotonic times at which the writer's commit of frames seq-1, seq-2, … had
//               returned (so a reader knows when a frame it never saw became readable)
//   words 11…   pattern_word(tag, i): any mix of two frames fails the check
//
// Words are little-endian uint64; a frame is a whole number of words (1920×1200×3 and points of
// 24 bytes both are). LiDAR frames of the real sim_replay_pcap carry no pattern: they are
// checked by their structure and by the writer's XXH3 checksum (see verify_points).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace soak {

inline constexpr std::uint64_t kMagic = 0x314B414F534D4953ull;  // "SIMSOAK1"
inline constexpr std::uint64_t kVideoTag = 0x5649444500000000ull;
inline constexpr std::size_t kHistory = 8;
inline constexpr std::size_t kHeaderWords = 3 + kHistory;

// splitmix64's finaliser.
inline std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
inline std::uint64_t index_word(std::uint64_t index) { return mix(index + 0x9E3779B97F4A7C15ull); }
inline std::uint64_t tag_word(std::uint64_t tag) { return mix(tag ^ 0xD1B54A32D192ED03ull); }
// Every word of a frame differs from the same word of any other frame, and a writer fills a
// frame at memory speed: a precomputed index_word table XOR one tag word.
// The frames of the generated video are flat instead (one byte value per picture, so a lossless
// codec keeps the file small and the replay decodes it quickly); any two still differ in every word.
inline bool is_video(std::uint64_t tag) { return (tag & ~0xFFull) == kVideoTag; }
inline std::uint64_t pattern_word(std::uint64_t tag, std::uint64_t index) {
  if (is_video(tag)) return 0x0101010101010101ull * (0x10 + 0x1F * (tag & 0x7));
  return index_word(index) ^ tag_word(tag);
}

inline std::uint64_t word_at(std::span<const std::byte> frame, std::size_t index) {
  std::uint64_t w;
  std::memcpy(&w, frame.data() + index * 8, 8);
  return w;
}

// Fills a frame: header, history (newest first), pattern; `index_words` holds index_word(i)
// for every word of the frame (the writer computes it once).
inline void fill(std::span<std::byte> frame, std::uint64_t tag, std::span<const std::int64_t> history,
                 std::span<const std::uint64_t> index_words) {
  const std::size_t words = frame.size() / 8;
  auto* out = reinterpret_cast<std::uint64_t*>(frame.data());  // slots are 64-byte aligned
  const std::uint64_t t = tag_word(tag);
  for (std::size_t i = kHeaderWords; i < words; ++i) out[i] = index_words[i] ^ t;
  out[0] = kMagic;
  out[1] = tag;
  out[2] = history.size();
  for (std::size_t i = 0; i < kHistory; ++i) {
    out[3 + i] = i < history.size() ? static_cast<std::uint64_t>(history[i]) : 0;
  }
}

enum class Verdict { whole, torn, not_ours };

// Checks the header and every `stride`-th pattern word plus the last one (a tear is a run of
// bytes of another frame: a stride of 64 words finds any run of 512 bytes or more; the XXH3
// checksum the writers add covers every byte on the copying reads).
inline Verdict verify(std::span<const std::byte> frame, std::size_t stride = 64) {
  const std::size_t words = frame.size() / 8;
  if (words < kHeaderWords || frame.size() % 8 != 0) return Verdict::not_ours;
  if (word_at(frame, 0) != kMagic) return Verdict::not_ours;
  const std::uint64_t tag = word_at(frame, 1);
  if (word_at(frame, 2) > kHistory) return Verdict::torn;
  for (std::size_t i = kHeaderWords; i < words; i += stride) {
    if (word_at(frame, i) != pattern_word(tag, i)) return Verdict::torn;
  }
  if (word_at(frame, words - 1) != pattern_word(tag, words - 1)) return Verdict::torn;
  return Verdict::whole;
}

// The commit-return time of frame (seq - back) carried by frame seq, or 0 if not carried.
inline std::int64_t carried_publish(std::span<const std::byte> frame, std::uint64_t back) {
  if (frame.size() < kHeaderWords * 8 || word_at(frame, 0) != kMagic) return 0;
  if (back == 0 || back > word_at(frame, 2) || back > kHistory) return 0;
  return static_cast<std::int64_t>(word_at(frame, 2 + back));
}

// A LiDAR frame of sim_replay_pcap (sim::LidarPoint, 24 bytes): whole means a whole number of
// points, every coordinate finite and within 1 km, every ring below 256.
inline bool verify_points(std::span<const std::byte> frame) {
  constexpr std::size_t kPoint = 24;
  if (frame.size() % kPoint != 0) return false;
  for (std::size_t at = 0; at < frame.size(); at += kPoint * 7) {  // every 7th point
    float xyz[3];
    std::memcpy(xyz, frame.data() + at, sizeof xyz);
    for (float v : xyz) {
      if (!std::isfinite(v) || std::fabs(v) > 1000.0f) return false;
    }
  }
  return true;
}

}  // namespace soak
