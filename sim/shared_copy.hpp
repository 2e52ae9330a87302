// SPDX-License-Identifier: Apache-2.0
// Copying a payload out of a slot the writer may be overwriting at the same moment.
//
// The seqlock read (docs/protocol.md) copies first and validates after, so the copy may race
// with the writer; the result is thrown away when it did. ThreadSanitizer cannot know that and
// would report the intended race, so in TSan builds the copy is a plain loop TSan does not watch.
// Every other access (sequence words, metadata) stays atomic and fully checked by TSan.
#pragma once

#include <cstddef>
#include <cstring>

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SIM_TSAN 1
#endif
#endif
#if defined(__SANITIZE_THREAD__)
#define SIM_TSAN 1
#endif

namespace sim::detail {

#ifdef SIM_TSAN
__attribute__((no_sanitize("thread"))) inline void copy_from_shared(void* dst, const void* src,
                                                                    std::size_t n) noexcept {
  auto* d = static_cast<volatile unsigned char*>(dst);
  const auto* s = static_cast<const volatile unsigned char*>(src);
  for (std::size_t i = 0; i < n; ++i) d[i] = s[i];
}
#else
inline void copy_from_shared(void* dst, const void* src, std::size_t n) noexcept {
  std::memcpy(dst, src, n);
}
#endif

}  // namespace sim::detail
