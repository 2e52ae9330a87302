// SPDX-License-Identifier: Apache-2.0
#include "sim/reader.hpp"

#include <dirent.h>
#include <sched.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <cerrno>
#include <thread>

#include "futex.hpp"
#include "region_file.hpp"
#include "clock_block.hpp"
#include "sensor_block.hpp"
#include "shared_copy.hpp"
#include "sim/clock.hpp"
#include "reader_wait.hpp"
#include "wake_plan.hpp"

namespace sim {

using namespace detail;

namespace {
// How many times a read retries a copy the writer overwrote before reporting an overrun.
constexpr int kMaxAttempts = 16;
// How often an idle reader asks the kernel whether the writer's lock is still held.
constexpr std::int64_t kLivenessCheckPeriodNs = 20'000'000;
// How long one futex sleep lasts at most, so a reader notices a region replaced by a new writer.
constexpr std::int64_t kWaitSliceNs = 100'000'000;
// A reader that may not write the wait page cannot ask to be woken, so it polls this often.
constexpr std::int64_t kPollSleepNs = 1'000'000;

// What a read found in the newest slot before copying it.
struct Snapshot {
  std::uint64_t seq;
  std::uint64_t size;
  std::int64_t stamp_ns;
  std::int64_t publish_ns;
  std::int64_t receive_ns;
  std::uint64_t checksum;
  std::uint32_t stamp_clock;
};

enum class Begin { ready, idle, lapped, invalid, reopened };

// How long a polling reader spins before it looks at the writer's liveness again.
constexpr std::int64_t kPollSliceNs = 20'000'000;
// Adaptive readers of this process spinning now; with each region's leases, this keeps spinners
// to the cores the process may use minus one, so the writer and other work always have a core.
std::atomic<int> spinners_in_this_process{0};

// Tells the core this is a spin loop (frees the pipeline for the other hyperthread).
inline void cpu_relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield" ::: "memory");
#endif
}

// Cores this process may run on, minus one: how many of its readers may spin at once.
int spin_limit_for_this_process() noexcept {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return 0;
  return std::max(0, CPU_COUNT(&set) - 1);
}
}  // namespace

// A token no other reader on the machine uses, for the reader's wait slot (WaitPage::asleep).
std::uint64_t new_reader_token() noexcept {
  static std::atomic<std::uint32_t> readers_in_this_process{0};
  const std::uint32_t n = readers_in_this_process.fetch_add(1, std::memory_order_relaxed);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(getpid())) << 32) | (n + 1);
}

struct Reader::Impl {
  std::string name;
  ReaderOptions options;
  // Shared with every Borrow taken from it, so a borrowed frame stays mapped however often the
  // region is replaced while it is held.
  std::shared_ptr<const RegionFile> file;
  const RegionHeader* header = nullptr;
  Layout layout;
  bool checksum = false;
  std::uint64_t last_seq = 0;
  std::int64_t opened_ns = 0;
  std::int64_t next_liveness_check_ns = 0;
  bool writer_alive_cached = false;
  const std::uint64_t token = new_reader_token();
  std::optional<std::size_t> wait_slot;  // this reader's slot in the wait page, if it got one
  ReaderStats stats;
  WakePlanner planner;
  WakeLateness wake_late;  // how late this reader's timed sleeps wake (adaptive mode)
  int spin_limit = 0;  // spinners allowed at once (cores of this process minus one), at open

  void adopt(RegionFile&& f) {
    file = std::make_shared<const RegionFile>(std::move(f));
    header = file->header();
    layout = from_record(file->identity().layout);
    checksum = (file->identity().flags & kFlagChecksum) != 0;
    opened_ns = monotonic_ns();
    next_liveness_check_ns = 0;
    claim_wait_slot();
  }

  // Takes a free slot of the wait page: the one whose lock no live reader holds. A mark left in
  // it proves its last owner died asleep, and comes out of the sleeper count.
  void claim_wait_slot() noexcept {
    wait_slot.reset();
    WaitPage* wait = file->wait_page();
    if (wait == nullptr) return;
    const std::size_t first = static_cast<std::size_t>(token % kReaderSlots);
    for (std::size_t i = 0; i < kReaderSlots; ++i) {
      const std::size_t slot = (first + i) % kReaderSlots;
      if (!try_lock_byte(file->fd(), kReaderLockBase + static_cast<off_t>(slot), true)) continue;
      if (wait->asleep[slot].exchange(0, std::memory_order_acq_rel) != 0) {
        wait->sleepers.fetch_sub(1, std::memory_order_relaxed);
      }
      wait_slot = slot;
      return;
    }
  }

  const std::byte* slot(std::uint64_t seq) const noexcept {
    return file->base() + file->identity().slot_offset[seq & 1];
  }
  const SlotMeta& meta(std::uint64_t seq) const noexcept { return header->slots[seq & 1]; }
  std::uint64_t capacity() const noexcept { return file->identity().capacity; }

  // After copying: did the slot keep the frame for the whole copy?
  bool unchanged(std::uint64_t seq) const noexcept {
    std::atomic_thread_fence(std::memory_order_acquire);
    return meta(seq).seq.load(std::memory_order_relaxed) == seq;
  }

  // Opens the name again if it now holds another region (a new writer replaced this one).
  bool reopen_if_replaced() noexcept {
    if (name_refers_to(name, file->inode())) return false;
    auto fresh = RegionFile::open_for_reading(name, options.trust);
    if (!fresh) return false;
    adopt(std::move(*fresh));
    ++stats.reopens;
    return true;
  }

  bool writer_alive(bool force) noexcept {
    const std::int64_t now = monotonic_ns();
    if (force || now >= next_liveness_check_ns) {
      writer_alive_cached = writer_lock_held(file->fd());
      next_liveness_check_ns = now + kLivenessCheckPeriodNs;
      if (!writer_alive_cached && reopen_if_replaced()) {
        writer_alive_cached = writer_lock_held(file->fd());
      }
    }
    return writer_alive_cached;
  }

  // Why there is no new frame: the writer is gone, the stream is stale, or simply nothing new.
  ReadStatus idle_status() noexcept {
    if (!writer_alive(false)) return ReadStatus::writer_gone;
    if (options.stale_after.count() > 0) {
      const std::int64_t newest =
          std::max(header->liveness.latest_publish_ns.load(std::memory_order_relaxed), opened_ns);
      if (monotonic_ns() - newest > options.stale_after.count()) return ReadStatus::stale;
    }
    return ReadStatus::no_new_frame;
  }

  std::uint64_t latest() const noexcept {
    return header->publication.latest_seq.load(std::memory_order_acquire);
  }

  // Whether read() or borrow() would find a frame now: a newest number this reader has not
  // returned, whose frame is in this region (a region that replaced another carries the old
  // numbering on before its writer's first frame) or was already overtaken by a newer one.
  bool deliverable() const noexcept {
    const std::uint64_t seq = latest();
    if (seq == 0 || seq == last_seq) return false;
    return (meta(seq).seq.load(std::memory_order_acquire) & ~kWritingBit) >= seq;
  }

  // Counts this reader as a sleeper, so the writer's next publish wakes the futex word. False if
  // nothing would wake it (a writer that predates wakes_every_publish and a reader that may not
  // write the wait page): it must then poll.
  bool begin_sleep() noexcept {
    if (WaitPage* wait = file->wait_page()) {
      if (wait_slot) wait->asleep[*wait_slot].store(token, std::memory_order_relaxed);
      wait->sleepers.fetch_add(1, std::memory_order_seq_cst);
      std::atomic_thread_fence(std::memory_order_seq_cst);
      return true;
    }
    // A reader that may not write the region (another user's group stream): the writer wakes
    // the futex on every publish, and the value check covers a publish since `seen` was read.
    return header->publication.wakes_every_publish.load(std::memory_order_relaxed) != 0;
  }
  void end_sleep() noexcept {
    WaitPage* wait = file->wait_page();
    if (wait == nullptr) return;
    // Take this reader's mark back out, unless the writer already did (it cannot tell a
    // reader that is about to sleep from a dead one only while that reader's lock is held).
    std::uint64_t mine = token;
    if (!wait_slot ||
        wait->asleep[*wait_slot].compare_exchange_strong(mine, 0, std::memory_order_acq_rel)) {
      wait->sleepers.fetch_sub(1, std::memory_order_relaxed);
    }
  }

  // Sleeps until the futex word moves away from `word` or `until` (CLOCK_MONOTONIC) comes.
  void sleep_until(const std::atomic<std::uint32_t>& word, std::uint32_t seen,
                   std::int64_t until) noexcept {
    if (begin_sleep()) {
      if (!deliverable()) futex_wait_until(&word, seen, until);
      end_sleep();
    } else {
      // A writer that predates wakes_every_publish: nothing would wake this reader.
      const std::int64_t nap = std::min(until - monotonic_ns(), kPollSleepNs);
      if (nap > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(nap));
    }
  }

  // Looks at the name again if the region was replaced or the writer seems gone (both cheap,
  // rate-limited); true if this reader now reads another region.
  bool refresh() noexcept {
    const std::uint64_t reopens = stats.reopens;
    if (header->publication.retired.load(std::memory_order_acquire) != 0) reopen_if_replaced();
    writer_alive(false);  // also reopens the name if a new writer replaced the region
    return stats.reopens != reopens;
  }

  StreamTiming timing() const noexcept {
    const Liveness& l = header->liveness;
    return {l.latest_publish_ns.load(std::memory_order_relaxed), l.period_ns.load(std::memory_order_relaxed),
            l.jitter_ns.load(std::memory_order_relaxed),
            l.frames_this_writer.load(std::memory_order_relaxed)};
  }

  // Spins until a frame is deliverable or `until` comes; true if one came. No system call:
  // monotonic_ns() is a vDSO read.
  bool spin_until(std::int64_t until) noexcept {
    ++stats.spins;
    const std::int64_t from = monotonic_ns();
    std::int64_t now = from;
    bool caught = false;
    while (now < until) {
      for (int i = 0; i < 32 && !caught; ++i) {
        caught = deliverable();
        if (!caught) cpu_relax();
      }
      now = monotonic_ns();
      if (caught) break;
    }
    stats.spin_ns += now - from;
    if (caught) ++stats.caught_spinning;
    return caught;
  }

  // An adaptive spin, if this reader may take one of the region's spin leases and the process
  // has a core to spare; false (nothing done) if it may not, and then it should sleep instead.
  bool try_adaptive_spin(std::int64_t now, std::int64_t until) noexcept {
    WaitPage* wait = file->wait_page();
    if (wait == nullptr || spin_limit <= 0) return false;  // a reader that cannot count itself
    if (spinners_in_this_process.fetch_add(1, std::memory_order_acq_rel) >= spin_limit) {
      spinners_in_this_process.fetch_sub(1, std::memory_order_relaxed);
      return false;
    }
    const std::size_t limit = std::min<std::size_t>(kSpinLeases, static_cast<std::size_t>(spin_limit));
    const int lease = SpinLeases::acquire(wait->spin_lease, limit, now, until);
    if (lease >= 0) {
      spin_until(until);
      SpinLeases::release(wait->spin_lease, lease, until);
    }
    spinners_in_this_process.fetch_sub(1, std::memory_order_relaxed);
    return lease >= 0;
  }

  // One step of a wait that found nothing deliverable at `now`; the caller loops.
  void wait_step(const std::atomic<std::uint32_t>& word, std::uint32_t seen, std::int64_t now,
                 std::int64_t deadline) noexcept {
    const std::int64_t slice_end = std::min(deadline, now + kWaitSliceNs);
    switch (options.wait_mode) {
      case WaitMode::block: sleep_until(word, seen, slice_end); return;
      case WaitMode::poll: spin_until(std::min(deadline, now + kPollSliceNs)); return;
      case WaitMode::adaptive: break;
    }
    const WakeStep step = planner.next(now, timing(), wake_late.ns());
    switch (step.action) {
      case WakeStep::Action::sleep: {
        const std::int64_t until = std::min(step.until, slice_end);
        sleep_until(word, seen, until);
        // Learn how late the deadline wake-ups come. Woken by the deadline: the lateness itself.
        // Woken by a publish after the deadline had passed: the timer had not woken it yet, so
        // it is later than that (leaving these out would teach the reader only its luckier
        // wake-ups, and its spin window would open too late to catch frames).
        if (until == step.until) {
          const std::int64_t late = monotonic_ns() - until;
          if (!deliverable()) {
            wake_late.add(late);
          } else if (late > wake_late.ns()) {
            wake_late.add_at_least(late);
          }
        }
        return;
      }
      case WakeStep::Action::spin:
        if (try_adaptive_spin(now, std::min(step.until, deadline))) return;
        [[fallthrough]];  // no core to spare: sleep like a blocking reader
      case WakeStep::Action::block: sleep_until(word, seen, slice_end); return;
    }
  }

  // First half of a seqlock read: finds the newest frame and its metadata, if it is new.
  Begin begin(Snapshot& s) noexcept {
    if (header->publication.retired.load(std::memory_order_acquire) != 0 && reopen_if_replaced()) {
      return Begin::reopened;
    }
    const std::uint64_t seq = latest();
    if (seq == 0 || seq == last_seq) return Begin::idle;
    const SlotMeta& m = meta(seq);
    const std::uint64_t in_slot = m.seq.load(std::memory_order_acquire);
    if (in_slot != seq) {
      // Later number: the writer lapped us. Earlier or none: the frame is not in this region
      // (a writer replaced the region and has not published in it yet).
      return (in_slot & ~kWritingBit) > seq ? Begin::lapped : Begin::idle;
    }
    s.seq = seq;
    s.size = m.size.load(std::memory_order_relaxed);
    s.stamp_ns = m.stamp_ns.load(std::memory_order_relaxed);
    s.publish_ns = m.publish_ns.load(std::memory_order_relaxed);
    s.receive_ns = m.receive_ns.load(std::memory_order_relaxed);
    s.checksum = m.checksum.load(std::memory_order_relaxed);
    s.stamp_clock = m.stamp_clock.load(std::memory_order_relaxed);
    if (s.size > capacity()) {
      // A torn metadata read is retried; a length the writer really published is a bad region.
      return unchanged(seq) ? Begin::invalid : Begin::lapped;
    }
    return Begin::ready;
  }

  void deliver(const Snapshot& s, FrameInfo& info) noexcept {
    if (last_seq != 0 && s.seq > last_seq + 1) stats.skipped += s.seq - last_seq - 1;
    last_seq = s.seq;
    ++stats.frames;
    info.seq = s.seq;
    info.stamp_ns = s.stamp_ns;
    info.publish_ns = s.publish_ns;
    info.receive_ns = s.receive_ns;
    info.size = s.size;
    info.layout = layout;
    // One load of a word in the header page the frame's metadata already brought in. After the
    // acquire of the frame's slot: a description set before the frame was published is seen.
    info.sensor_generation = sensor_generation(header->sensor.word.load(std::memory_order_relaxed));
    info.clock_generation = clock_generation(header->clock.word.load(std::memory_order_relaxed));
    // A value beyond the enum (a damaged slot) reads as unknown rather than as a wrong clock.
    info.stamp_clock = s.stamp_clock <= static_cast<std::uint32_t>(StampClock::host_arrival)
                           ? static_cast<StampClock>(s.stamp_clock)
                           : StampClock::unknown;
  }

  bool checksum_ok(const void* data, const Snapshot& s) noexcept {
    if (!checksum || !options.verify_checksum) return true;
    if (XXH3_64bits(data, s.size) == s.checksum) return true;
    ++stats.checksum_failures;
    last_seq = s.seq;  // do not offer the same bad frame again
    return false;
  }
};

Expected<Reader> Reader::open(std::string_view name, const ReaderOptions& options) {
  auto file = RegionFile::open_for_reading(name, options.trust);
  if (!file) return file.error();
  auto impl = std::make_unique<Impl>();
  impl->name = std::string(name);
  impl->options = options;
  if (options.wait_mode == WaitMode::adaptive) impl->spin_limit = spin_limit_for_this_process();
  impl->adopt(std::move(*file));
  return Reader(std::move(impl));
}

Reader::Reader(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;
Reader::~Reader() = default;

ReadStatus Reader::read(std::byte* out_data, std::size_t out_size, FrameInfo& info) noexcept {
  const std::span<std::byte> out(out_data, out_size);
  Impl& r = *impl_;
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Snapshot s{};
    switch (r.begin(s)) {
      case Begin::idle: return r.idle_status();
      case Begin::invalid: return ReadStatus::region_invalid;
      case Begin::reopened: continue;
      case Begin::lapped: ++r.stats.overruns; continue;
      case Begin::ready: break;
    }
    if (s.size > out.size()) return ReadStatus::buffer_too_small;
    copy_from_shared(out.data(), r.slot(s.seq), s.size);
    if (!r.unchanged(s.seq)) {
      ++r.stats.overruns;
      continue;
    }
    if (!r.checksum_ok(out.data(), s)) return ReadStatus::checksum_mismatch;
    r.deliver(s, info);
    return ReadStatus::new_frame;
  }
  return ReadStatus::overrun;
}

Borrow Reader::borrow() noexcept {
  Impl& r = *impl_;
  Borrow b;
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Snapshot s{};
    switch (r.begin(s)) {
      case Begin::idle: b.status_ = r.idle_status(); return b;
      case Begin::invalid: b.status_ = ReadStatus::region_invalid; return b;
      case Begin::reopened: continue;
      case Begin::lapped: ++r.stats.overruns; continue;
      case Begin::ready: break;
    }
    const std::byte* data = r.slot(s.seq);
    if (r.checksum && r.options.verify_checksum) {
      const std::uint64_t hash = XXH3_64bits(data, s.size);
      if (!r.unchanged(s.seq)) {
        ++r.stats.overruns;
        continue;
      }
      if (hash != s.checksum) {
        ++r.stats.checksum_failures;
        r.last_seq = s.seq;
        b.status_ = ReadStatus::checksum_mismatch;
        return b;
      }
    }
    r.deliver(s, b.info_);
    b.status_ = ReadStatus::new_frame;
    b.bytes_ = {data, s.size};
    b.slot_seq_ = &r.meta(s.seq).seq;
    b.mapping_ = r.file;
    return b;
  }
  b.status_ = ReadStatus::overrun;
  return b;
}

bool Borrow::still_valid() const noexcept {
  if (status_ != ReadStatus::new_frame || slot_seq_ == nullptr) return false;
  std::atomic_thread_fence(std::memory_order_acquire);
  return static_cast<const std::atomic<std::uint64_t>*>(slot_seq_)->load(
             std::memory_order_relaxed) == info_.seq;
}

ReadStatus Reader::wait(std::chrono::nanoseconds timeout) noexcept {
  Impl& r = *impl_;
  const std::int64_t start = monotonic_ns();
  // Saturating: kForever (or any timeout past the year 2262) must not wrap into the past.
  const std::int64_t budget = std::max<std::int64_t>(timeout.count(), 0);
  const std::int64_t deadline =
      budget > std::numeric_limits<std::int64_t>::max() - start ? std::numeric_limits<std::int64_t>::max()
                                                               : start + budget;
  for (;;) {
    if (r.refresh()) continue;  // look again, at the new region

    const std::atomic<std::uint32_t>& futex_word = r.header->publication.futex_word;
    const std::uint32_t word = futex_word.load(std::memory_order_acquire);
    if (r.deliverable()) return ReadStatus::new_frame;
    const std::int64_t now = monotonic_ns();
    if (now >= deadline) return r.idle_status();
    // Wait in slices, so a reader notices a region replaced by a new writer or a dead writer.
    r.wait_step(futex_word, word, now, deadline);
  }
}

bool detail::ReaderWaitAccess::refresh(Reader& reader) noexcept { return reader.impl_->refresh(); }
bool detail::ReaderWaitAccess::deliverable(const Reader& reader) noexcept {
  return reader.impl_->deliverable();
}
const std::atomic<std::uint32_t>& detail::ReaderWaitAccess::futex_word(const Reader& reader) noexcept {
  return reader.impl_->header->publication.futex_word;
}
bool detail::ReaderWaitAccess::begin_sleep(Reader& reader) noexcept { return reader.impl_->begin_sleep(); }
void detail::ReaderWaitAccess::end_sleep(Reader& reader) noexcept { reader.impl_->end_sleep(); }
void detail::ReaderWaitAccess::sleep_until(Reader& reader, std::uint32_t seen, std::int64_t until) noexcept {
  reader.impl_->sleep_until(reader.impl_->header->publication.futex_word, seen, until);
}
ReadStatus detail::ReaderWaitAccess::idle_status(Reader& reader) noexcept {
  return reader.impl_->idle_status();
}
void detail::ReaderWaitAccess::skip_to_newest(Reader& reader) noexcept {
  Reader::Impl& r = *reader.impl_;
  if (r.deliverable()) r.last_seq = r.latest();
}

ReadStatus Reader::read_next(std::byte* out_data, std::size_t out_size, FrameInfo& info,
                             std::chrono::nanoseconds timeout) noexcept {
  const ReadStatus waited = wait(timeout);
  if (waited != ReadStatus::new_frame) return waited;
  return read(out_data, out_size, info);
}

void Reader::set_wait_mode(WaitMode mode) noexcept {
  impl_->options.wait_mode = mode;
  if (mode == WaitMode::adaptive && impl_->spin_limit == 0) {
    impl_->spin_limit = spin_limit_for_this_process();
  }
}

bool Reader::writer_alive() noexcept { return impl_->writer_alive(true); }

std::chrono::nanoseconds Reader::newest_age() const noexcept {
  const std::int64_t published =
      impl_->header->liveness.latest_publish_ns.load(std::memory_order_relaxed);
  if (published == 0) return std::chrono::nanoseconds(-1);
  return std::chrono::nanoseconds(monotonic_ns() - published);
}

const std::string& Reader::name() const noexcept { return impl_->name; }
std::uint64_t Reader::capacity() const noexcept { return impl_->capacity(); }
const Layout& Reader::layout() const noexcept { return impl_->layout; }
bool Reader::checksum() const noexcept { return impl_->checksum; }
ReaderStats Reader::stats() const noexcept { return impl_->stats; }

StreamStatus Reader::status() noexcept {
  const bool alive = impl_->writer_alive(true);  // first: it may move the reader to a new region
  const Impl& r = *impl_;
  const RegionFile& file = *r.file;
  const RegionHeader& h = *r.header;
  StreamStatus s;
  s.name = r.name;
  s.layout = r.layout;
  s.capacity = r.capacity();
  s.checksum = r.checksum;
  s.frames_published = h.liveness.frames_published.load(std::memory_order_relaxed);
  s.latest_seq = h.publication.latest_seq.load(std::memory_order_relaxed);
  s.latest_publish_ns = h.liveness.latest_publish_ns.load(std::memory_order_relaxed);
  s.heartbeat_ns = h.liveness.heartbeat_ns.load(std::memory_order_relaxed);
  s.max_publish_interval_ns = h.liveness.max_publish_interval_ns.load(std::memory_order_relaxed);
  s.period_ns = h.liveness.period_ns.load(std::memory_order_relaxed);
  s.jitter_ns = h.liveness.jitter_ns.load(std::memory_order_relaxed);
  s.frames_this_writer = h.liveness.frames_this_writer.load(std::memory_order_relaxed);
  s.writer_start_realtime_ns = h.writer.start_realtime_ns.load(std::memory_order_relaxed);
  s.writer_pid = h.writer.pid.load(std::memory_order_relaxed);
  s.writer_command = writer_name(h.writer, h.program);
  s.writer_alive = alive;
  if (const WaitPage* wp = file.wait_page()) {
    s.sleeping_readers = wp->sleepers.load(std::memory_order_relaxed);
  }
  s.owner_uid = file.owner_uid();
  s.owner_gid = file.owner_gid();
  s.mode = file.mode();
  auto sensor = read_sensor_block(h.sensor, &s.sensor_generation);
  if (sensor) {
    s.sensor = std::move(*sensor);
  } else {
    s.sensor_problem = sensor.error().message;
  }
  auto clock = read_clock_block(h.clock, &s.clock_generation);
  if (clock) {
    s.clock = std::move(*clock);
  } else {
    s.clock_problem = clock.error().message;
  }
  return s;
}

Expected<std::optional<SensorInfo>> Reader::sensor_info() const {
  return read_sensor_block(impl_->header->sensor);
}

Expected<std::optional<ClockStatus>> Reader::clock() const {
  return read_clock_block(impl_->header->clock);
}

double StreamStatus::rate_hz(std::int64_t now_monotonic_ns) const noexcept {
  if (period_ns <= 0 || frames_this_writer < 2 || latest_publish_ns == 0) return 0.0;
  if (now_monotonic_ns - latest_publish_ns > 3 * period_ns) return 0.0;  // it stopped
  return 1e9 / static_cast<double>(period_ns);
}

std::vector<std::string> list_streams() {
  std::vector<std::string> names;
  const std::string dir(kRegionDir);
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) return names;
  while (const dirent* entry = readdir(d)) {
    const std::string_view file(entry->d_name);
    if (!file.starts_with(kRegionPrefix)) continue;
    std::string name(1, '/');  // built in place: GCC 12's -Wrestrict misfires on "/" + string
    name += file.substr(kRegionPrefix.size());
    if (name_problem(name).empty()) names.push_back(name);
  }
  closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

Expected<StreamStatus> inspect(std::string_view name) {
  ReaderOptions options;
  options.trust = Trust::any_owner();  // looking is harmless; sim_ls lists every stream
  auto reader = Reader::open(name, options);
  if (!reader) return reader.error();
  return reader->status();
}

Expected<void> destroy(std::string_view name, bool force) {
  if (const std::string problem = name_problem(name); !problem.empty()) {
    return Error{ErrorCode::invalid_name, problem};
  }
  const std::string path = region_path(name);
  for (int attempt = 0; attempt < 8; ++attempt) {
    // O_NONBLOCK: never wait on a FIFO planted under the name. Read-write when allowed, because
    // the remover's lock is exclusive; an odd or foreign file is removed without it.
    int fd = open(path.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0 && (errno == EACCES || errno == ENXIO)) {
      fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
    }
    if (fd < 0 && errno == ENOENT) {
      return Error{ErrorCode::not_found, "no stream named " + std::string(name) + " exists"};
    }
    struct stat st {};
    const bool region_like = fd >= 0 && fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
    if (region_like && !force) {
      // Writer::create takes the writer lock, then checks this lock; this takes this lock, then
      // checks the writer lock. Either this sees the writer (and refuses), or the writer sees this
      // (and waits until the name is gone): a starting writer is never left in a removed file.
      const bool locked = try_lock_byte(fd, kRemoverLockByte, /*exclusive=*/true);
      if (writer_lock_held(fd)) {
        close(fd);
        return Error{ErrorCode::writer_exists,
                     "stream " + std::string(name) + " has a live writer; stop it first or use --force"};
      }
      if (!name_refers_to(name, st.st_ino)) {  // replaced meanwhile: look at the new file
        close(fd);
        continue;
      }
      if (!locked && (fcntl(fd, F_GETFL) & O_ACCMODE) == O_RDWR) {
        close(fd);  // another remover is at work; look again
        continue;
      }
    }
    const int unlinked = unlink(path.c_str());
    const int err = errno;
    if (fd >= 0) close(fd);  // releases the remover lock, after the name is gone
    if (unlinked != 0 && err != ENOENT) {
      return errno_error(ErrorCode::permission_denied,
                         "cannot remove " + path + "; only its owner (or root) can", err);
    }
    return {};
  }
  return Error{ErrorCode::system_error,
               "stream " + std::string(name) + " kept changing while it was being removed; try again"};
}

}  // namespace sim
