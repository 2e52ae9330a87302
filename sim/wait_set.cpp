// SPDX-License-Identifier: Apache-2.0
#include "sim/wait_set.hpp"

#include <sys/eventfd.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <ctime>
#include <limits>
#include <thread>

#include "futex.hpp"
#include "reader_wait.hpp"
#include "sim/clock.hpp"

namespace sim {

using detail::ReaderWaitAccess;

namespace {
// The longest single sleep: the set then looks again for replaced regions and dead writers.
constexpr std::int64_t kWaitSliceNs = 100'000'000;
// Sleep at most this long when some stream cannot wake the set (a writer too old to wake readers
// that may not write its wait page): that stream is polled at this period.
constexpr std::int64_t kPollSleepNs = 1'000'000;
// A full set's futex_waitv has no room for the wakeup's word: it sleeps at most this long and
// looks at the wakeup between sleeps.
constexpr std::int64_t kFullSetWakeupPollNs = 10'000'000;

#ifndef SYS_futex_waitv
#define SYS_futex_waitv 449  // the same number on x86-64 and aarch64
#endif
// struct futex_waitv of <linux/futex.h> (Linux 5.16), spelled out for older kernel headers.
struct FutexWaitv {
  std::uint64_t val;
  std::uint64_t uaddr;
  std::uint32_t flags;
  std::uint32_t reserved;
};
constexpr std::uint32_t kFutex2SizeU32 = 0x02;  // shared (not FUTEX2_PRIVATE): other processes

// Whether this kernel has futex_waitv: asked once with an empty list (EINVAL if it exists).
bool kernel_has_futex_waitv() noexcept {
  static const bool has = [] {
    const long rc = syscall(SYS_futex_waitv, nullptr, 0, 0, nullptr, CLOCK_MONOTONIC);
    return !(rc < 0 && errno == ENOSYS);
  }();
  return has;
}

std::int64_t deadline_after(std::chrono::nanoseconds timeout) noexcept {
  const std::int64_t start = monotonic_ns();
  const std::int64_t budget = std::max<std::int64_t>(timeout.count(), 0);
  return budget > std::numeric_limits<std::int64_t>::max() - start
             ? std::numeric_limits<std::int64_t>::max()
             : start + budget;
}
}  // namespace

struct WaitSet::Impl {
  WaitSetOptions options;
  WaitSetStrategy strategy;
  std::vector<Reader*> readers;
  Wakeup* wakeup = nullptr;
  bool woken = false;  // the last wait ended by the wakeup
  std::size_t next_ready = 0;   // where the next look for a ready reader starts (fairness)
  std::size_t next_sleep = 0;   // the stream the next round-robin slice sleeps on

  std::optional<std::size_t> find_ready() noexcept {
    const std::size_t n = readers.size();
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (next_ready + k) % n;
      if (ReaderWaitAccess::deliverable(*readers[i])) {
        next_ready = (i + 1) % n;
        return i;
      }
    }
    return std::nullopt;
  }

  // Whether the wakeup was notified since the last wait that took it; takes it.
  bool take_wakeup() noexcept {
    return wakeup != nullptr && wakeup->pending_.load(std::memory_order_relaxed) != 0 &&
           wakeup->pending_.exchange(0, std::memory_order_acquire) != 0;
  }

  // One futex_waitv sleep on every stream's word (and the wakeup's); false if the kernel lacks
  // the call.
  bool sleep_on_all(const std::array<std::uint32_t, kMaxReaders>& seen, std::int64_t until) noexcept {
    const std::size_t n = readers.size();
    std::array<FutexWaitv, kMaxReaders> waits{};
    bool every_stream_wakes = true;
    for (std::size_t i = 0; i < n; ++i) {
      every_stream_wakes = ReaderWaitAccess::begin_sleep(*readers[i]) && every_stream_wakes;
      waits[i] = {seen[i], reinterpret_cast<std::uintptr_t>(&ReaderWaitAccess::futex_word(*readers[i])),
                  kFutex2SizeU32, 0};
    }
    std::size_t words = n;
    if (wakeup != nullptr && n < kMaxReaders) {
      // Sleeps only while nothing is pending: a notify() after take_wakeup() ends it at once.
      waits[words++] = {0, reinterpret_cast<std::uintptr_t>(&wakeup->pending_), kFutex2SizeU32, 0};
    } else if (wakeup != nullptr) {
      until = std::min(until, monotonic_ns() + kFullSetWakeupPollNs);
    }
    bool supported = true;
    if (!find_ready()) {
      if (!every_stream_wakes) until = std::min(until, monotonic_ns() + kPollSleepNs);
      timespec deadline{until / 1'000'000'000, until % 1'000'000'000};
      const long rc = syscall(SYS_futex_waitv, waits.data(), static_cast<unsigned>(words), 0, &deadline,
                              CLOCK_MONOTONIC);
      supported = !(rc < 0 && errno == ENOSYS);
    }
    for (std::size_t i = 0; i < n; ++i) ReaderWaitAccess::end_sleep(*readers[i]);
    return supported;
  }
};

WaitSet::WaitSet(const WaitSetOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
  impl_->strategy = options.strategy;
  if (impl_->strategy == WaitSetStrategy::automatic) {
    impl_->strategy =
        kernel_has_futex_waitv() ? WaitSetStrategy::futex_waitv : WaitSetStrategy::round_robin;
  }
}
WaitSet::WaitSet(WaitSet&&) noexcept = default;
WaitSet& WaitSet::operator=(WaitSet&&) noexcept = default;
WaitSet::~WaitSet() = default;

Expected<std::size_t> WaitSet::add(Reader& reader) {
  if (impl_->readers.size() >= kMaxReaders) {
    return Error{ErrorCode::invalid_argument,
                 "a wait set holds at most 128 readers; split the streams over two sets"};
  }
  // A reader counts itself as a sleeper once per sleep of the set; twice in the set, it would count
  // twice and take itself out once, raising the stream's sleeper count for good.
  const auto& readers = impl_->readers;
  if (const auto found = std::find(readers.begin(), readers.end(), &reader); found != readers.end()) {
    return Error{ErrorCode::invalid_argument,
                 "the reader of " + reader.name() + " is already in the wait set (index " +
                     std::to_string(found - readers.begin()) + "); add each reader once"};
  }
  impl_->readers.push_back(&reader);
  return impl_->readers.size() - 1;
}

void WaitSet::watch(Wakeup& wakeup) noexcept { impl_->wakeup = &wakeup; }

std::size_t WaitSet::size() const noexcept { return impl_->readers.size(); }
bool WaitSet::woken() const noexcept { return impl_->woken; }
WaitSetStrategy WaitSet::strategy() const noexcept { return impl_->strategy; }

bool WaitSet::ready(std::size_t index) const noexcept {
  return index < impl_->readers.size() && ReaderWaitAccess::deliverable(*impl_->readers[index]);
}

std::optional<std::size_t> WaitSet::wait(std::chrono::nanoseconds timeout) noexcept {
  Impl& s = *impl_;
  const std::int64_t deadline = deadline_after(timeout);
  const std::size_t n = s.readers.size();
  std::array<std::uint32_t, kMaxReaders> seen{};
  s.woken = false;
  for (;;) {
    if (s.take_wakeup()) {
      s.woken = true;
      return std::nullopt;
    }
    bool moved = false;
    for (Reader* r : s.readers) moved = ReaderWaitAccess::refresh(*r) || moved;
    if (moved) continue;  // look again, at the new regions
    for (std::size_t i = 0; i < n; ++i) {
      seen[i] = ReaderWaitAccess::futex_word(*s.readers[i]).load(std::memory_order_acquire);
    }
    if (auto ready = s.find_ready()) return ready;
    const std::int64_t now = monotonic_ns();
    if (now >= deadline) return std::nullopt;
    const std::int64_t until = std::min(deadline, now + kWaitSliceNs);
    if (n == 0 && s.wakeup != nullptr) {
      detail::futex_wait_until(&s.wakeup->pending_, 0, until);
      continue;
    }
    if (n == 0) {
      timespec ts{(until - now) / 1'000'000'000, (until - now) % 1'000'000'000};
      nanosleep(&ts, nullptr);
      continue;
    }
    if (s.strategy == WaitSetStrategy::futex_waitv) {
      if (!s.sleep_on_all(seen, until)) s.strategy = WaitSetStrategy::round_robin;
      continue;
    }
    // Round robin: one stream's own futex for one slice, then every stream is looked at again.
    const std::size_t i = s.next_sleep++ % n;
    ReaderWaitAccess::sleep_until(*s.readers[i], seen[i],
                                  std::min(until, now + s.options.round_robin_slice.count()));
  }
}

void Wakeup::notify() noexcept {
  // After whatever the notifying thread did (added work, asked to stop): the waiter that takes
  // the wakeup sees it.
  if (pending_.exchange(1, std::memory_order_release) == 0) detail::futex_wake_all(&pending_);
}

// --- StreamNotifier ---------------------------------------------------------------------------

struct StreamNotifier::Impl {
  std::vector<Reader> readers;  // the notifier's own: only its thread touches them
  std::unique_ptr<std::atomic<bool>[]> arrived;
  int event_fd = -1;
  std::atomic<bool> stop{false};
  Wakeup stop_wakeup;  // ends the thread's wait when the notifier closes
  std::thread thread;

  void run() noexcept {
    WaitSet set;
    for (Reader& r : readers) (void)set.add(r);
    set.watch(stop_wakeup);
    while (!stop.load(std::memory_order_relaxed)) {
      if (!set.wait(kForever)) continue;
      for (std::size_t i = 0; i < readers.size(); ++i) {
        if (!set.ready(i)) continue;
        ReaderWaitAccess::skip_to_newest(readers[i]);
        arrived[i].store(true, std::memory_order_release);
      }
      // After the flags: a drain() that sees the fd readable finds them set.
      const std::uint64_t one = 1;
      (void)!::write(event_fd, &one, sizeof one);
    }
  }

  ~Impl() {
    stop.store(true, std::memory_order_relaxed);
    stop_wakeup.notify();
    if (thread.joinable()) thread.join();
    if (event_fd >= 0) ::close(event_fd);
  }
};

Expected<StreamNotifier> StreamNotifier::open(const std::vector<std::string>& names,
                                              const ReaderOptions& options) {
  if (names.empty() || names.size() > WaitSet::kMaxReaders) {
    return Error{ErrorCode::invalid_argument, "a stream notifier needs 1 to 128 stream names"};
  }
  auto impl = std::make_unique<Impl>();
  ReaderOptions quiet = options;
  quiet.verify_checksum = false;  // it never reads a frame, only notices one
  quiet.wait_mode = WaitMode::block;
  for (const std::string& name : names) {
    auto reader = Reader::open(name, quiet);
    if (!reader) return reader.error();
    impl->readers.push_back(std::move(*reader));
  }
  impl->arrived = std::make_unique<std::atomic<bool>[]>(names.size());
  impl->event_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (impl->event_fd < 0) {
    return Error{ErrorCode::system_error, "cannot create an eventfd; the process is out of file descriptors"};
  }
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->run(); });
  return StreamNotifier(std::move(impl));
}

StreamNotifier::StreamNotifier(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
StreamNotifier::StreamNotifier(StreamNotifier&&) noexcept = default;
StreamNotifier& StreamNotifier::operator=(StreamNotifier&&) noexcept = default;
StreamNotifier::~StreamNotifier() = default;

int StreamNotifier::fd() const noexcept { return impl_->event_fd; }

std::vector<bool> StreamNotifier::drain() noexcept {
  std::uint64_t count = 0;
  (void)!::read(impl_->event_fd, &count, sizeof count);
  std::vector<bool> which(impl_->readers.size());
  for (std::size_t i = 0; i < which.size(); ++i) {
    which[i] = impl_->arrived[i].exchange(false, std::memory_order_acq_rel);
  }
  return which;
}

}  // namespace sim
