// SPDX-License-Identifier: Apache-2.0
// Waiting for several streams at once, and for streams inside someone else's event loop.
//
//   sim::WaitSet set;
//   const auto cam = set.add(camera_reader);
//   const auto lidar = set.add(lidar_reader);
//   while (auto ready = set.wait(100ms)) {
//     if (*ready == cam) camera_reader.read(buffer, info);   // or check set.ready(cam) and set.ready(lidar)
//   }
//
// The readers keep their own semantics (freshest frame, borrow, still_valid); the set only waits.
// A sim::Wakeup ends a wait from another thread (new work for the waiting thread, or stop).
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim {

// How a WaitSet sleeps on several streams.
enum class WaitSetStrategy {
  automatic,     // futex_waitv where the kernel has it (Linux >= 5.16), else round_robin
  futex_waitv,   // one system call sleeps on every stream's futex word (ENOSYS: round_robin)
  round_robin,   // sleeps on one stream at a time in short slices, checking all between slices:
                 // works on any kernel; a frame on another stream waits up to one slice
};

struct WaitSetOptions {
  WaitSetStrategy strategy = WaitSetStrategy::automatic;
  // Length of one round-robin slice: the worst extra latency of that strategy.
  std::chrono::nanoseconds round_robin_slice{1'000'000};
};

// Ends the wait of the WaitSet that watches it, from any thread: for a thread that sleeps on
// streams and must also notice other work (a stream to add, a request to stop). A notify() while
// the set is not waiting ends its next wait at once; one wait that ends this way takes every
// notify() made before it.
class Wakeup {
 public:
  Wakeup() = default;
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  void notify() noexcept;

 private:
  friend class WaitSet;
  std::atomic<std::uint32_t> pending_{0};  // 1 from notify() until a wait takes it; a futex word
};

// Waits until any of its readers has a frame read() or borrow() would deliver. Holds references:
// each added Reader must outlive the set (or be removed first) and must not move. Not thread-safe:
// use it from the thread that reads the readers.
class WaitSet {
 public:
  explicit WaitSet(const WaitSetOptions& options = {});
  WaitSet(WaitSet&&) noexcept;
  WaitSet& operator=(WaitSet&&) noexcept;
  WaitSet(const WaitSet&) = delete;
  WaitSet& operator=(const WaitSet&) = delete;
  ~WaitSet();

  // Adds a reader; returns its index in the set (0, 1, …). At most kMaxReaders.
  static constexpr std::size_t kMaxReaders = 128;  // futex_waitv's limit
  Expected<std::size_t> add(Reader& reader);
  std::size_t size() const noexcept;

  // Also ends each wait when `wakeup` is notified (one wakeup per set; a second replaces the
  // first). The wakeup must outlive the set. A set of kMaxReaders readers notices it within
  // 10 ms (futex_waitv takes 128 words, all the readers'); any other set at once, or within one
  // round-robin slice.
  void watch(Wakeup& wakeup) noexcept;

  // Sleeps until some reader has a deliverable frame, the watched wakeup is notified, or the
  // timeout passes (kForever: none). The index of a ready reader (readers are taken in turn, so a
  // busy stream does not hide a quieter one), or nothing at the timeout or wakeup (woken() says
  // which; a wakeup comes first: a ready reader stays ready for the next wait).
  [[nodiscard]] std::optional<std::size_t> wait(std::chrono::nanoseconds timeout) noexcept;
  template <typename Rep, typename Period>
  [[nodiscard]] std::optional<std::size_t> wait(std::chrono::duration<Rep, Period> timeout) noexcept {
    return wait(saturating_nanoseconds(timeout));
  }
  // Whether the last wait() ended by the wakeup (else by a ready reader or its timeout).
  [[nodiscard]] bool woken() const noexcept;
  // Whether reader `index` has a deliverable frame now (no system call).
  [[nodiscard]] bool ready(std::size_t index) const noexcept;
  // The strategy in use: automatic resolves to futex_waitv or round_robin at the first wait.
  WaitSetStrategy strategy() const noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// A file descriptor that becomes readable when any of its streams has a new frame, for
// epoll, poll, Boost.Asio or a ROS 2 executor. A small thread waits on the streams with its own
// readers (opened by name, so the caller's readers stay single-threaded) and counts their new
// frames into an eventfd. After the fd reports readable, call drain() and read your own readers.
// Like a new Reader, it counts a stream's newest frame at open() as new.
class StreamNotifier {
 public:
  static Expected<StreamNotifier> open(const std::vector<std::string>& names,
                                       const ReaderOptions& options = {});
  StreamNotifier(StreamNotifier&&) noexcept;
  StreamNotifier& operator=(StreamNotifier&&) noexcept;
  StreamNotifier(const StreamNotifier&) = delete;
  StreamNotifier& operator=(const StreamNotifier&) = delete;
  ~StreamNotifier();  // stops the thread and closes the fd

  // Readable (EPOLLIN) while frames arrived that drain() has not taken yet. Owned by the notifier.
  int fd() const noexcept;
  // Resets the fd; returns for each stream (in the order of `names`) whether it had new frames.
  std::vector<bool> drain() noexcept;

  struct Impl;

 private:
  explicit StreamNotifier(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim
