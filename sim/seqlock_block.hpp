// SPDX-License-Identifier: Apache-2.0
// A record in the region's header page that its one writer rewrites now and then (the sensor
// description, the clock record), guarded by a seqlock word with a generation (internal):
//   bit 0      set while the writer rewrites the record (readers copy again)
//   bit 1      a record is present (clear: the writer has none)
//   bits 2..63 the generation: +1 on every change, carried over when a region is replaced
#pragma once

#include <sched.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>

#include "region.hpp"
#include "shared_copy.hpp"
#include "sim/clock.hpp"
#include "sim/result.hpp"

namespace sim::detail {

// The generation of a word while a record is present, else 0.
constexpr std::uint64_t block_generation(std::uint64_t word) noexcept {
  return (word & kSensorPresent) != 0 ? word / kSensorGenerationStep : 0;
}

// A new region's word, carrying on the generation of the region it replaces (`previous_word`, 0
// for a new stream), so a reader that reopens the name never sees an old generation again.
inline void start_block(std::atomic<std::uint64_t>& word, std::uint64_t previous_word) noexcept {
  word.store(previous_word & ~(kSensorWriting | kSensorPresent), std::memory_order_relaxed);
}

// Stores `record` (present) or zeros (absent); either way the generation moves on.
template <typename Record>
void write_block(std::atomic<std::uint64_t>& word, Record& shared, const Record& record,
                 bool present) noexcept {
  const std::uint64_t old_word = word.load(std::memory_order_relaxed);
  const std::uint64_t generation_bits = old_word & ~(kSensorWriting | kSensorPresent);
  // Odd first, keeping the old presence: frames read meanwhile still carry the old generation.
  word.store(old_word | kSensorWriting, std::memory_order_relaxed);
  // Orders the mark before the record's stores (pairs with the readers' fence after their copy).
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(static_cast<void*>(&shared), &record, sizeof record);
  word.store((generation_bits + kSensorGenerationStep) | (present ? kSensorPresent : 0),
             std::memory_order_release);
}

// Copies a record out of a block the writer may be changing and hands it to `decode`
// (Record -> Expected<Value>, checking it like a header). nullopt: the stream has none. An Error:
// the block is damaged or kept changing. `what` names the record in sentences ("sensor
// description"). `generation` (optional) receives the generation of the copy returned.
template <typename Value, typename Record, typename Decode>
Expected<std::optional<Value>> read_block(const std::atomic<std::uint64_t>& word,
                                          const Record& shared, const char* what,
                                          std::uint64_t* generation, Decode decode) {
  // A rewrite is a copy of about 1 KiB: a block that stays in the middle of the same one this
  // long belongs to a writer that stopped there (died, or paused: it may still go on).
  constexpr std::int64_t kStuckUpdateNs = 50'000'000;
  // A reader gives up after this long if every copy overlapped another update.
  constexpr std::int64_t kMaxReadNs = 1'000'000'000;
  const auto damaged = [what](const std::string& fault) {
    return Error{ErrorCode::region_invalid,
                 std::string("the stream's ") + what + " is damaged: " + fault + "; restart its writer"};
  };
  Record record;
  const std::int64_t start = monotonic_ns();
  std::uint64_t odd_word = 0;  // the update the writer was in the middle of when first seen
  std::int64_t odd_since = 0;
  for (;;) {
    const std::uint64_t before = word.load(std::memory_order_acquire);
    if ((before & kSensorWriting) != 0) {
      const std::int64_t now = monotonic_ns();
      if (before != odd_word) {
        odd_word = before;
        odd_since = now;
      } else if (now - odd_since > kStuckUpdateNs) {
        // Review turn 4 L8: a live writer stopped (SIGSTOP, a debugger) or starved on a loaded
        // host looks the same from here, so the advice covers both.
        return Error{ErrorCode::region_invalid,
                     std::string("the stream's ") + what +
                         " cannot be read: its writer stopped in the middle of changing it over 50 ms "
                         "ago; read it again later (a writer that is paused or starved finishes the "
                         "change when it runs again; one that died must be restarted)"};
      }
      sched_yield();
      continue;
    }
    if (monotonic_ns() - start > kMaxReadNs) {
      return Error{ErrorCode::system_error, std::string("the stream's ") + what +
                                                " changed during every attempt to read it; try again"};
    }
    if (generation != nullptr) *generation = block_generation(before);
    if ((before & kSensorPresent) == 0) return std::optional<Value>{};
    copy_from_shared(&record, &shared, sizeof record);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (word.load(std::memory_order_relaxed) != before) continue;
    if (block_generation(before) == 0) return damaged("it is marked present in generation 0");
    Expected<Value> value = decode(record);
    if (!value) return damaged(value.error().message);
    return std::optional<Value>{std::move(*value)};
  }
}

}  // namespace sim::detail
