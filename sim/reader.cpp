// SPDX-License-Identifier: Apache-2.0
#include "sim/reader.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <thread>

#include "futex.hpp"
#include "region_file.hpp"
#include "shared_copy.hpp"
#include "sim/clock.hpp"

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
};

enum class Begin { ready, idle, lapped, invalid, reopened };
}  // namespace

struct Reader::Impl {
  std::string name;
  ReaderOptions options;
  RegionFile file;
  // The region before the last replacement stays mapped, so a Borrow taken from it just before
  // the reader moved on still points at mapped memory (still_valid() tells it is outdated).
  RegionFile previous_file;
  const RegionHeader* header = nullptr;
  Layout layout;
  bool checksum = false;
  std::uint64_t last_seq = 0;
  std::int64_t opened_ns = 0;
  std::int64_t next_liveness_check_ns = 0;
  bool writer_alive_cached = false;
  ReaderStats stats;

  void adopt(RegionFile&& f) {
    previous_file = std::move(file);
    file = std::move(f);
    header = file.header();
    layout = from_record(file.identity().layout);
    checksum = (file.identity().flags & kFlagChecksum) != 0;
    opened_ns = monotonic_ns();
    next_liveness_check_ns = 0;
  }

  const std::byte* slot(std::uint64_t seq) const noexcept {
    return file.base() + file.identity().slot_offset[seq & 1];
  }
  const SlotMeta& meta(std::uint64_t seq) const noexcept { return header->slots[seq & 1]; }
  std::uint64_t capacity() const noexcept { return file.identity().capacity; }

  // After copying: did the slot keep the frame for the whole copy?
  bool unchanged(std::uint64_t seq) const noexcept {
    std::atomic_thread_fence(std::memory_order_acquire);
    return meta(seq).seq.load(std::memory_order_relaxed) == seq;
  }

  // Opens the name again if it now holds another region (a new writer replaced this one).
  bool reopen_if_replaced() noexcept {
    if (name_refers_to(name, file.inode())) return false;
    auto fresh = RegionFile::open_for_reading(name, options.accept_other_owner);
    if (!fresh) return false;
    adopt(std::move(*fresh));
    ++stats.reopens;
    return true;
  }

  bool writer_alive(bool force) noexcept {
    const std::int64_t now = monotonic_ns();
    if (force || now >= next_liveness_check_ns) {
      writer_alive_cached = writer_lock_held(file.fd());
      next_liveness_check_ns = now + kLivenessCheckPeriodNs;
      if (!writer_alive_cached && reopen_if_replaced()) {
        writer_alive_cached = writer_lock_held(file.fd());
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
  auto file = RegionFile::open_for_reading(name, options.accept_other_owner);
  if (!file) return file.error();
  auto impl = std::make_unique<Impl>();
  impl->name = std::string(name);
  impl->options = options;
  impl->adopt(std::move(*file));
  return Reader(std::move(impl));
}

Reader::Reader(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;
Reader::~Reader() = default;

ReadStatus Reader::read(std::span<std::byte> out, FrameInfo& info) noexcept {
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
  const std::int64_t deadline = monotonic_ns() + std::max<std::int64_t>(timeout.count(), 0);
  for (;;) {
    const std::uint64_t reopens = r.stats.reopens;
    if (r.header->publication.retired.load(std::memory_order_acquire) != 0) {
      r.reopen_if_replaced();
    }
    r.writer_alive(false);  // also reopens the name if a new writer replaced the region
    if (r.stats.reopens != reopens) continue;  // look again, at the new region

    const std::atomic<std::uint32_t>& futex_word = r.header->publication.futex_word;
    const std::uint32_t word = futex_word.load(std::memory_order_acquire);
    const std::uint64_t seq = r.latest();
    if (seq != 0 && seq != r.last_seq) return ReadStatus::new_frame;
    const std::int64_t now = monotonic_ns();
    if (now >= deadline) return r.idle_status();
    const std::int64_t until = std::min(deadline, now + kWaitSliceNs);
    if (WaitPage* wp = r.file.wait_page()) {
      wp->sleepers.fetch_add(1, std::memory_order_seq_cst);
      std::atomic_thread_fence(std::memory_order_seq_cst);
      if (r.latest() == r.last_seq) futex_wait_until(&futex_word, word, until);
      wp->sleepers.fetch_sub(1, std::memory_order_relaxed);
    } else {
      const std::int64_t nap = std::min(until - now, kPollSleepNs);
      std::this_thread::sleep_for(std::chrono::nanoseconds(nap));
    }
  }
}

ReadStatus Reader::read_next(std::span<std::byte> out, FrameInfo& info,
                             std::chrono::nanoseconds timeout) noexcept {
  const ReadStatus waited = wait(timeout);
  if (waited != ReadStatus::new_frame) return waited;
  return read(out, info);
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
  s.writer_start_realtime_ns = h.writer.start_realtime_ns.load(std::memory_order_relaxed);
  s.writer_pid = h.writer.pid.load(std::memory_order_relaxed);
  s.writer_command = unpack_command(h.writer.command);
  s.writer_alive = alive;
  if (const WaitPage* wp = r.file.wait_page()) {
    s.sleeping_readers = wp->sleepers.load(std::memory_order_relaxed);
  }
  return s;
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
    if (name_problem(name).empty() && name.find(".tmp") == std::string::npos) {
      names.push_back(name);
    }
  }
  closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

Expected<StreamStatus> inspect(std::string_view name) {
  ReaderOptions options;
  options.accept_other_owner = true;  // looking is harmless; sim_ls lists every stream
  auto reader = Reader::open(name, options);
  if (!reader) return reader.error();
  return reader->status();
}

std::optional<Error> destroy(std::string_view name, bool force) {
  if (const std::string problem = name_problem(name); !problem.empty()) {
    return Error{ErrorCode::invalid_name, problem};
  }
  const std::string path = region_path(name);
  const int fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0 && errno == ENOENT) {
    return Error{ErrorCode::not_found, "no stream named " + std::string(name) + " exists"};
  }
  if (fd >= 0) {
    const bool alive = writer_lock_held(fd);
    close(fd);
    if (alive && !force) {
      return Error{ErrorCode::writer_exists, "stream " + std::string(name) +
                                                 " has a live writer; stop it first or use --force"};
    }
  }
  // A symlink or other odd file under our prefix is removed without being opened.
  if (unlink(path.c_str()) != 0 && errno != ENOENT) {
    return errno_error(ErrorCode::permission_denied, "cannot remove " + path, errno);
  }
  return std::nullopt;
}

}  // namespace sim
