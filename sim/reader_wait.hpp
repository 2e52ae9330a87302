// SPDX-License-Identifier: Apache-2.0
// What a WaitSet needs of each reader's wake-up machinery (internal; defined in reader.cpp).
#pragma once

#include <atomic>
#include <cstdint>

#include "sim/reader.hpp"

namespace sim::detail {

struct ReaderWaitAccess {
  // Reopens a replaced region / notices a dead writer; true if the reader moved to a new region.
  static bool refresh(Reader& reader) noexcept;
  // Whether read() or borrow() would deliver a frame now.
  static bool deliverable(const Reader& reader) noexcept;
  // The word the writer adds one to (and wakes) on every publish.
  static const std::atomic<std::uint32_t>& futex_word(const Reader& reader) noexcept;
  // Counts the reader as a sleeper of its stream (false: nothing would wake it; poll instead).
  static bool begin_sleep(Reader& reader) noexcept;
  static void end_sleep(Reader& reader) noexcept;
  // Reader::wait's own single-stream sleep (begin_sleep, futex, end_sleep).
  static void sleep_until(Reader& reader, std::uint32_t seen, std::int64_t until) noexcept;
  // Why nothing is deliverable: writer_gone, stale or no_new_frame.
  static ReadStatus idle_status(Reader& reader) noexcept;
  // Marks the newest frame as returned without reading it (a notifier only counts frames).
  static void skip_to_newest(Reader& reader) noexcept;
};

}  // namespace sim::detail
