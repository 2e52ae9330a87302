// SPDX-License-Identifier: Apache-2.0
#include "sim/writer.hpp"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

#include "futex.hpp"
#include "period_estimate.hpp"
#include "region_file.hpp"
#include "clock_block.hpp"
#include "sensor_block.hpp"
#include "sim/clock.hpp"

namespace sim {

using namespace detail;

struct detail::WriterState {
  std::string name;
  std::uint64_t capacity = 0;
  Layout layout;
  bool checksum = false;
  // Group-readable streams have readers that may not write the wait page, so they cannot say
  // they sleep: the writer then wakes the futex on every publish (one cheap system call).
  bool wakes_every_publish = false;
  // Shared with whoever holds Writer::mapping(), so views into the region (a binding's numpy
  // views of a committed loan) stay readable after the writer is gone; the writer lock goes with
  // the WriterState all the same (its destructor releases it).
  std::shared_ptr<RegionFile> file = std::make_shared<RegionFile>();
  RegionHeader* header = nullptr;
  std::uint64_t last_seq = 0;  // newest published frame
  std::int64_t last_publish_ns = 0;
  std::int64_t max_interval_ns = 0;
  std::uint64_t frames_published = 0;  // by this writer
  detail::PeriodEstimate period;
  std::int64_t last_heal_ns = 0;  // last scan for sleepers that died asleep
  bool loan_open = false;
  // The StampClock of the clock record set last; set_clock may run on another thread.
  std::atomic<std::uint32_t> stamp_clock{0};

  // Optional idle heartbeat.
  std::thread heartbeat_thread;
  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_stop_cv;
  bool heartbeat_stop = false;

  std::byte* slot(std::uint64_t seq) const noexcept {
    return file->base() + file->identity().slot_offset[seq & 1];
  }
  SlotMeta& meta(std::uint64_t seq) const noexcept { return header->slots[seq & 1]; }

  // Marks the slot of the next frame as being written. Readers that are still copying the frame
  // it held (two frames ago) see the mark when they re-check the slot afterwards and retry.
  void begin_write() noexcept {
    meta(last_seq + 1).seq.store((last_seq + 1) | kWritingBit, std::memory_order_relaxed);
    // Orders the mark before every payload store that follows (pairs with the readers' acquire
    // fence after their copy; a plain release store would not order *later* stores).
    std::atomic_thread_fence(std::memory_order_release);
  }

  // Refreshes the heartbeat `every` period from a thread while no frame is published.
  void start_heartbeat(std::chrono::milliseconds every) {
    heartbeat_thread = std::thread([this, every] {
      std::unique_lock lock(heartbeat_mutex);
      while (!heartbeat_stop_cv.wait_for(lock, every, [this] { return heartbeat_stop; })) {
        header->liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
      }
    });
  }

  void stop_heartbeat() {
    if (!heartbeat_thread.joinable()) return;
    {
      std::lock_guard lock(heartbeat_mutex);
      heartbeat_stop = true;
    }
    heartbeat_stop_cv.notify_all();
    heartbeat_thread.join();
  }

  // Takes the marks of readers that died asleep out of the sleeper count, so the writer's fast
  // path (no system call while nobody sleeps) comes back by itself. A reader holds the lock of
  // its slot for its whole life; the kernel drops it when the reader dies, however it dies.
  void heal_dead_sleepers(std::int64_t now) noexcept {
    if (now - last_heal_ns < kHealPeriodNs) return;
    last_heal_ns = now;
    WaitPage& wait = *file->wait_page();
    for (std::size_t i = 0; i < kReaderSlots; ++i) {
      std::uint64_t token = wait.asleep[i].load(std::memory_order_acquire);
      if (token == 0 || byte_locked(file->fd(), kReaderLockBase + static_cast<off_t>(i))) continue;
      if (wait.asleep[i].compare_exchange_strong(token, 0, std::memory_order_acq_rel)) {
        wait.sleepers.fetch_sub(1, std::memory_order_relaxed);
      }
    }
  }
  static constexpr std::int64_t kHealPeriodNs = 100'000'000;

  ~WriterState() {
    stop_heartbeat();
    if (header != nullptr) {
      // Release the writer lock first, then wake sleeping readers, so they see it released.
      unlock_writer(file->fd());
      header->publication.futex_word.fetch_add(1, std::memory_order_release);
      futex_wake_all(&header->publication.futex_word);
    }
  }
};

namespace {

WriteStatus publish(WriterState& w, std::uint64_t size, std::int64_t stamp_ns,
                    std::int64_t receive_ns) noexcept;

bool compatible(const Identity& id, const StreamSpec& spec, std::uint64_t capacity) {
  return id.capacity == capacity && from_record(id.layout) == spec.layout &&
         ((id.flags & kFlagChecksum) != 0) == spec.checksum;
}

// `previous` is the header of the region this one replaces (null for a new stream): frame numbers
// and the sensor description's generation carry on from it, so readers that reopen the name never
// see an old number again.
void initialise_header(RegionHeader& h, std::uint64_t capacity, const StreamSpec& spec,
                       const RegionHeader* previous) {
  const std::uint64_t first_seq =
      previous != nullptr ? previous->publication.latest_seq.load(std::memory_order_acquire) : 0;
  start_sensor_block(h.sensor,
                     previous != nullptr ? previous->sensor.word.load(std::memory_order_acquire) : 0);
  start_clock_block(h.clock,
                    previous != nullptr ? previous->clock.word.load(std::memory_order_acquire) : 0);
  const Geometry g = geometry_for(capacity);
  Identity& id = h.identity;
  id.version = kVersion;
  id.header_size = sizeof(RegionHeader);
  id.file_size = g.file_size;
  id.capacity = capacity;
  id.slot_offset[0] = g.slot_offset[0];
  id.slot_offset[1] = g.slot_offset[1];
  id.flags = spec.checksum ? kFlagChecksum : 0;
  id.created_realtime_ns = realtime_ns();
  id.layout = to_record(spec.layout);
  h.publication.latest_seq.store(first_seq, std::memory_order_relaxed);
  // Neither slot holds a readable frame yet: a reader of `first_seq` (carried over from a
  // replaced region) finds the slot's word different and reports nothing.
  h.slots[0].seq.store(kWritingBit, std::memory_order_relaxed);
  h.slots[1].seq.store(kWritingBit, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  id.magic = kMagic;
}

// Why a writer of `spec` cannot take `name` now, naming the live writer; for the error message.
Error live_writer_error(const StreamSpec& spec, RegionFile& file) {
  std::string who;
  Identity id{};
  if (file.read_identity(id) && header_problem(id, file.file_size()).empty() &&
      file.map_read_write()) {
    who = " (pid " + std::to_string(file.header()->writer.pid.load()) + ", " +
          writer_name(file.header()->writer, file.header()->program) + ")";
  }
  return Error{ErrorCode::writer_exists, "stream " + spec.name + " already has a live writer" + who +
                                             "; stop it first or use another name"};
}

// What is wrong with `spec`, whose slots hold `capacity` bytes, in one sentence; nullopt if nothing.
std::optional<Error> spec_problem(const StreamSpec& spec, std::uint64_t capacity) {
  if (const std::string problem = name_problem(spec.name); !problem.empty()) {
    return Error{ErrorCode::invalid_name, problem};
  }
  if (capacity == 0 || capacity > kMaxCapacity) {
    return Error{ErrorCode::invalid_argument,
                 "stream " + spec.name + " needs a capacity between 1 byte and 1 TiB per frame"};
  }
  if (const std::string problem = spec.layout.check(capacity); !problem.empty()) {
    return Error{ErrorCode::invalid_argument, "stream " + spec.name + ": " + problem};
  }
  if (spec.sensor) {
    if (const std::string problem = sensor_info_problem(*spec.sensor); !problem.empty()) {
      return Error{ErrorCode::invalid_argument, "stream " + spec.name + ": " + problem};
    }
  }
  // Write access to the region is the power to truncate it (SIGBUS for the writer) or to forge
  // frames, so only the owner ever has it; readers of the group never need it (see wakes_every_publish).
  if ((spec.mode & ~0644u) != 0 || (spec.mode & 0600u) != 0600u) {
    return Error{ErrorCode::invalid_argument,
                 "stream " + spec.name +
                     ": mode must give the owner read and write and others at most read (0600, 0640 "
                     "or 0644)"};
  }
  return std::nullopt;
}

// Makes `file`, the writer-locked region this writer now owns, the writer's.
void adopt_region(WriterState& w, RegionFile&& file) {
  *w.file = std::move(file);  // the lock stays with this open file
  w.header = w.file->header();
  w.last_seq = w.header->publication.latest_seq.load(std::memory_order_acquire);
}

// Says who writes the region now and starts this writer's own liveness figures afresh. A new
// region gets all of it before it gets its name, so a reader that opens the stream at once
// already finds the writer and its sensor description.
void announce_writer(RegionHeader& h, const StreamSpec& spec, bool wakes_every_publish) {
  h.writer.pid.store(getpid(), std::memory_order_relaxed);
  h.writer.attach_count.fetch_add(1, std::memory_order_relaxed);
  h.writer.start_realtime_ns.store(realtime_ns(), std::memory_order_relaxed);
  store_writer_names(h.writer, h.program);
  h.publication.wakes_every_publish.store(wakes_every_publish ? 1 : 0, std::memory_order_relaxed);
  h.liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
  h.liveness.max_publish_interval_ns.store(0, std::memory_order_relaxed);
  h.liveness.period_ns.store(0, std::memory_order_relaxed);
  h.liveness.jitter_ns.store(0, std::memory_order_relaxed);
  h.liveness.frames_this_writer.store(0, std::memory_order_relaxed);
  // This writer's description replaces whatever the region held (a previous writer's, maybe of
  // another sensor); a region that never had one is left untouched.
  if (spec.sensor || h.sensor.word.load(std::memory_order_relaxed) != 0) {
    write_sensor_block(h.sensor, spec.sensor);
  }
  // A previous writer's clock record says nothing of this one's clock: gone until it sets one.
  if ((h.clock.word.load(std::memory_order_relaxed) & kSensorPresent) != 0) {
    write_clock_block(h.clock, std::nullopt);
  }
}

// What claim_existing() did with the region the name holds.
enum class Claim {
  taken_over,  // it is this writer's now
  replace,     // it must be replaced by a new region (it is kept locked until then)
  look_again,  // the name changed meanwhile (removed, replaced, being removed)
};

// Locks the region `file` the name holds and takes it over when it fits `spec` (same layout,
// capacity and checksum setting, one name); otherwise moves it into `old`, still locked, so no
// other writer can slip in before it is replaced.
Expected<Claim> claim_existing(WriterState& w, const StreamSpec& spec, std::uint64_t capacity,
                               RegionFile& file, RegionFile& old) {
  if (!try_lock_writer(file.fd())) return live_writer_error(spec, file);
  // destroy() takes the remover lock, then checks the writer lock; this writer took the
  // writer lock and now checks the remover lock. Whichever order the two ran in, one sees the
  // other: a removal in progress is waited out and the name looked at again.
  if (byte_locked(file.fd(), kRemoverLockByte)) {
    unlock_writer(file.fd());
    wait_until_unlocked(file.fd(), kRemoverLockByte);
    return Claim::look_again;
  }
  if (!name_refers_to(spec.name, file.inode())) return Claim::look_again;  // removed or replaced
  Identity id{};
  const bool valid = file.read_identity(id) && header_problem(id, file.file_size()).empty();
  // A second name for the same file (a hard link) would let its readers read this stream
  // under that name: such a region is replaced, never taken over.
  if (valid && compatible(id, spec, capacity) && file.link_count() == 1) {
    if (auto mapped = file.map_read_write(); !mapped) return mapped.error();
    adopt_region(w, std::move(file));
    fchmod(w.file->fd(), spec.mode & 0777);
    announce_writer(*w.header, spec, w.wakes_every_publish);
    return Claim::taken_over;
  }
  // Layout or capacity changed, or the region is corrupt or linked twice.
  if (valid) (void)file.map_read_write();  // to carry its numbering on; unmapped: start afresh
  old = std::move(file);
  return Claim::replace;
}

// Builds a new region for `spec` and gives it the name, replacing `old` when `replace` (old is
// then retired, so its readers reopen the name). False when another writer won the race for a
// new name: the caller looks again.
Expected<bool> create_region(WriterState& w, const StreamSpec& spec, std::uint64_t capacity,
                             RegionFile& old, bool replace) {
  auto created = RegionFile::create_unnamed(geometry_for(capacity).file_size, spec.mode);
  if (!created) return created.error();
  if (!try_lock_writer(created->fd())) {
    return Error{ErrorCode::system_error, "cannot lock the new region of " + spec.name};
  }
  initialise_header(*created->header(), capacity, spec, old.header());
  announce_writer(*created->header(), spec, w.wakes_every_publish);
  created->reload_identity();
  if (auto published = created->publish_as(spec.name, replace); !published) {
    if (published.error().code == ErrorCode::writer_exists) return false;
    return published.error();
  }
  if (old.header() != nullptr) {
    // Tell readers of the old region to reopen the name.
    old.header()->publication.retired.store(1, std::memory_order_release);
    old.header()->publication.futex_word.fetch_add(1, std::memory_order_release);
    futex_wake_all(&old.header()->publication.futex_word);
  }
  adopt_region(w, std::move(*created));
  return true;
}

// Gives `w` the region of `spec.name`: the one there (taken over), or a new one. Each pass looks
// at what the name holds now; another pass is needed when a second writer won a race for a new
// name, or when destroy() was removing the region while this writer opened it.
Expected<void> attach_region(WriterState& w, const StreamSpec& spec, std::uint64_t capacity) {
  for (int attempt = 0; attempt < 8; ++attempt) {
    auto existing = RegionFile::open_for_writing(spec.name);
    RegionFile old;
    if (existing) {
      auto claim = claim_existing(w, spec, capacity, *existing, old);
      if (!claim) return claim.error();
      if (*claim == Claim::taken_over) return {};
      if (*claim == Claim::look_again) continue;
    } else if (existing.error().code != ErrorCode::not_found) {
      return existing.error();
    }
    auto created = create_region(w, spec, capacity, old, /*replace=*/existing.has_value());
    if (!created) return created.error();
    if (*created) return {};
  }
  return Error{ErrorCode::writer_exists,
               "stream " + spec.name + " is being created or removed by another process; try again"};
}

}  // namespace

Expected<Writer> Writer::create(const StreamSpec& spec) {
  const std::uint64_t capacity = spec.capacity != 0 ? spec.capacity : spec.layout.min_capacity();
  if (auto problem = spec_problem(spec, capacity)) return *problem;

  auto impl = std::make_unique<WriterState>();
  impl->name = spec.name;
  impl->capacity = capacity;
  impl->layout = spec.layout;
  impl->checksum = spec.checksum;
  impl->wakes_every_publish = (spec.mode & 0044u) != 0;
  if (auto attached = attach_region(*impl, spec, capacity); !attached) return attached.error();

  if (spec.lock_memory && mlock(impl->file->base(), impl->file->file_size()) != 0) {
    return errno_error(ErrorCode::system_error,
                       "cannot lock stream " + spec.name +
                           " in memory; raise RLIMIT_MEMLOCK (ulimit -l) or drop lock_memory",
                       errno);
  }
  if (spec.heartbeat_period.count() > 0) impl->start_heartbeat(spec.heartbeat_period);
  return Writer(std::move(impl));
}

std::uint64_t region_size(std::uint64_t capacity) noexcept { return geometry_for(capacity).file_size; }

Writer::Writer(std::unique_ptr<WriterState> impl) noexcept : impl_(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&&) noexcept = default;
Writer::~Writer() = default;

WriteStatus Writer::write(const std::byte* frame_data, std::size_t frame_size, std::int64_t stamp_ns,
                          std::int64_t receive_ns) noexcept {
  const std::span<const std::byte> frame(frame_data, frame_size);
  if (!impl_) return WriteStatus::closed;
  if (impl_->loan_open) return WriteStatus::loan_open;
  if (frame.size() > impl_->capacity) return WriteStatus::too_large;
  impl_->begin_write();
  // An empty frame may come with no buffer at all (C: SIM_writeData(w, NULL, 0)).
  if (!frame.empty()) std::memcpy(impl_->slot(impl_->last_seq + 1), frame.data(), frame.size());
  return publish(*impl_, frame.size(), stamp_ns, receive_ns);
}

Loan Writer::loan() noexcept {
  if (!impl_ || impl_->loan_open) return Loan(nullptr, {});
  impl_->begin_write();
  impl_->loan_open = true;
  return Loan(impl_.get(), {impl_->slot(impl_->last_seq + 1), impl_->capacity});
}

namespace {

WriteStatus publish(WriterState& w, std::uint64_t size, std::int64_t stamp_ns,
                    std::int64_t receive_ns) noexcept {
  if (size > w.capacity) return WriteStatus::too_large;
  const std::uint64_t seq = w.last_seq + 1;
  SlotMeta& meta = w.meta(seq);
  const std::int64_t now = monotonic_ns();
  meta.size.store(size, std::memory_order_relaxed);
  meta.stamp_ns.store(stamp_ns, std::memory_order_relaxed);
  meta.publish_ns.store(now, std::memory_order_relaxed);
  meta.receive_ns.store(receive_ns, std::memory_order_relaxed);
  meta.stamp_clock.store(w.stamp_clock.load(std::memory_order_relaxed), std::memory_order_relaxed);
  meta.checksum.store(w.checksum ? XXH3_64bits(w.slot(seq), size) : 0, std::memory_order_relaxed);
  // The frame is complete: release it under its number, then make it the newest.
  meta.seq.store(seq, std::memory_order_release);
  Publication& pub = w.header->publication;
  pub.latest_seq.store(seq, std::memory_order_release);
  // +1 rather than the frame number: the word must change on every publish, also when a new
  // writer's first frame carries the number the last writer's exit already bumped the word to.
  pub.futex_word.fetch_add(1, std::memory_order_release);
  w.last_seq = seq;

  Liveness& live = w.header->liveness;
  if (w.last_publish_ns != 0) {
    const std::int64_t interval = now - w.last_publish_ns;
    if (interval > w.max_interval_ns) {
      w.max_interval_ns = interval;
      live.max_publish_interval_ns.store(w.max_interval_ns, std::memory_order_relaxed);
    }
    w.period.add(interval);
    live.period_ns.store(w.period.period_ns(), std::memory_order_relaxed);
    live.jitter_ns.store(w.period.jitter_ns(), std::memory_order_relaxed);
  }
  w.last_publish_ns = now;
  live.latest_publish_ns.store(now, std::memory_order_relaxed);
  live.heartbeat_ns.store(now, std::memory_order_relaxed);
  live.frames_published.fetch_add(1, std::memory_order_relaxed);
  live.frames_this_writer.store(++w.frames_published, std::memory_order_relaxed);

  // Dekker-style handshake with Reader::wait: either a sleeper sees the new frame before it
  // sleeps, or this load sees the sleeper and wakes it. No system call when nobody sleeps.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  const bool sleepers = w.file->wait_page()->sleepers.load(std::memory_order_relaxed) != 0;
  if (sleepers || w.wakes_every_publish) {
    const long woken = futex_wake_all(&pub.futex_word);
    // Counted sleepers but nobody woke: usually a reader just about to sleep, but perhaps one
    // that died asleep. Check (rarely) so the count does not stay raised forever.
    if (sleepers && woken == 0) w.heal_dead_sleepers(now);
  }
  return WriteStatus::ok;
}

}  // namespace

void Writer::heartbeat() noexcept {
  if (impl_) impl_->header->liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
}

Expected<void> Writer::set_sensor_info(const SensorInfo& info) {
  if (!impl_) return Error{ErrorCode::invalid_argument, "this writer was moved from"};
  if (const std::string problem = sensor_info_problem(info); !problem.empty()) {
    return Error{ErrorCode::invalid_argument, "stream " + impl_->name + ": " + problem};
  }
  write_sensor_block(impl_->header->sensor, info);
  return {};
}

Expected<void> Writer::set_clock(const ClockStatus& clock) {
  if (!impl_) return Error{ErrorCode::invalid_argument, "this writer was moved from"};
  if (const std::string problem = clock_status_problem(clock); !problem.empty()) {
    return Error{ErrorCode::invalid_argument, "stream " + impl_->name + ": " + problem};
  }
  write_clock_block(impl_->header->clock, clock);
  impl_->stamp_clock.store(static_cast<std::uint32_t>(clock.stamps), std::memory_order_relaxed);
  return {};
}

std::shared_ptr<const void> Writer::mapping() const noexcept {
  if (!impl_) return nullptr;
  return impl_->file;
}

const std::string& Writer::name() const noexcept { return impl_->name; }
std::uint64_t Writer::capacity() const noexcept { return impl_->capacity; }
const Layout& Writer::layout() const noexcept { return impl_->layout; }
std::uint64_t Writer::last_seq() const noexcept { return impl_->last_seq; }

Loan::Loan(Loan&& other) noexcept
    : writer_(std::exchange(other.writer_, nullptr)), bytes_(std::exchange(other.bytes_, {})) {}

Loan& Loan::operator=(Loan&& other) noexcept {
  if (this != &other) {
    release();
    writer_ = std::exchange(other.writer_, nullptr);
    bytes_ = std::exchange(other.bytes_, {});
  }
  return *this;
}

Loan::~Loan() { release(); }

void Loan::release() noexcept {
  if (writer_ != nullptr) writer_->loan_open = false;
  writer_ = nullptr;
  bytes_ = {};
}

WriteStatus Loan::commit(std::uint64_t size, std::int64_t stamp_ns, std::int64_t receive_ns) && noexcept {
  if (writer_ == nullptr) return WriteStatus::closed;
  const WriteStatus status = publish(*writer_, size, stamp_ns, receive_ns);
  release();
  return status;
}

}  // namespace sim
