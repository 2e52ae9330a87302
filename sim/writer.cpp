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
#include "region_file.hpp"
#include "sim/clock.hpp"

namespace sim {

using namespace detail;

struct detail::WriterState {
  std::string name;
  std::uint64_t capacity = 0;
  Layout layout;
  bool checksum = false;
  RegionFile file;
  RegionHeader* header = nullptr;
  std::uint64_t last_seq = 0;  // newest published frame
  std::int64_t last_publish_ns = 0;
  std::int64_t max_interval_ns = 0;
  std::uint64_t loans_started = 0;  // identifies the newest loan: only it may commit

  // Optional idle heartbeat.
  std::thread heartbeat_thread;
  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_stop_cv;
  bool heartbeat_stop = false;

  std::byte* slot(std::uint64_t seq) const noexcept {
    return file.base() + file.identity().slot_offset[seq & 1];
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

  void stop_heartbeat() {
    if (!heartbeat_thread.joinable()) return;
    {
      std::lock_guard lock(heartbeat_mutex);
      heartbeat_stop = true;
    }
    heartbeat_stop_cv.notify_all();
    heartbeat_thread.join();
  }

  ~WriterState() {
    stop_heartbeat();
    if (header != nullptr) {
      // Release the writer lock first, then wake sleeping readers, so they see it released.
      unlock_writer(file.fd());
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

void initialise_header(RegionHeader& h, std::uint64_t capacity, const StreamSpec& spec,
                       std::uint64_t first_seq) {
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

}  // namespace

Expected<Writer> Writer::create(const StreamSpec& spec) {
  if (const std::string problem = name_problem(spec.name); !problem.empty()) {
    return Error{ErrorCode::invalid_name, problem};
  }
  const std::uint64_t capacity = spec.capacity != 0 ? spec.capacity : spec.layout.min_capacity();
  if (capacity == 0 || capacity > kMaxCapacity) {
    return Error{ErrorCode::invalid_argument,
                 "stream " + spec.name + " needs a capacity between 1 byte and 1 TiB per frame"};
  }
  if (const std::string problem = spec.layout.check(capacity); !problem.empty()) {
    return Error{ErrorCode::invalid_argument, "stream " + spec.name + ": " + problem};
  }
  if ((spec.mode & ~0666u) != 0 || (spec.mode & 0600u) != 0600u) {
    return Error{ErrorCode::invalid_argument,
                 "stream " + spec.name + ": mode must give the owner read and write and no one execute"};
  }

  auto impl = std::make_unique<WriterState>();
  impl->name = spec.name;
  impl->capacity = capacity;
  impl->layout = spec.layout;
  impl->checksum = spec.checksum;

  // Two writers can race for a new name; the loser sees the winner's region on its next pass.
  for (int attempt = 0; attempt < 3; ++attempt) {
    auto existing = RegionFile::open_for_writing(spec.name);
    std::uint64_t first_seq = 0;
    bool replace = false;
    RegionFile old;
    if (existing) {
      RegionFile& file = *existing;
      if (!try_lock_writer(file.fd())) {
        std::string who;
        Identity id{};
        if (!file.read_identity(id) && header_problem(id, file.file_size()).empty() &&
            file.map_read_write() == std::nullopt) {
          who = " (pid " + std::to_string(file.header()->writer.pid.load()) + ", " +
                unpack_command(file.header()->writer.command) + ")";
        }
        return Error{ErrorCode::writer_exists, "stream " + spec.name + " already has a live writer" +
                                                   who + "; stop it first or use another name"};
      }
      Identity id{};
      const bool valid =
          !file.read_identity(id) && header_problem(id, file.file_size()).empty();
      if (valid && compatible(id, spec, capacity)) {
        if (auto error = file.map_read_write()) return *error;
        impl->file = std::move(file);  // take it over: the lock stays with this open file
        impl->header = impl->file.header();
        impl->last_seq = impl->header->publication.latest_seq.load(std::memory_order_acquire);
        fchmod(impl->file.fd(), spec.mode & 0777);
        break;
      }
      // Layout or capacity changed, or the region is corrupt: build a new one and replace it,
      // keeping the old one locked until then so no other writer can slip in.
      if (valid && file.map_read_write() == std::nullopt) {
        first_seq = file.header()->publication.latest_seq.load(std::memory_order_acquire);
      }
      old = std::move(file);
      replace = true;
    } else if (existing.error().code != ErrorCode::not_found) {
      return existing.error();
    }

    auto created = RegionFile::create_unnamed(geometry_for(capacity).file_size, spec.mode);
    if (!created) return created.error();
    if (!try_lock_writer(created->fd())) {
      return Error{ErrorCode::system_error, "cannot lock the new region of " + spec.name};
    }
    initialise_header(*created->header(), capacity, spec, first_seq);
    created->reload_identity();
    if (auto error = created->publish_as(spec.name, replace)) {
      if (error->code == ErrorCode::writer_exists) continue;  // lost the race: look again
      return *error;
    }
    if (old.header() != nullptr) {
      // Tell readers of the old region to reopen the name.
      old.header()->publication.retired.store(1, std::memory_order_release);
      old.header()->publication.futex_word.fetch_add(1, std::memory_order_release);
      futex_wake_all(&old.header()->publication.futex_word);
    }
    impl->file = std::move(*created);
    impl->header = impl->file.header();
    impl->last_seq = first_seq;
    break;
  }
  if (impl->header == nullptr) {
    return Error{ErrorCode::writer_exists,
                 "stream " + spec.name + " is being created by another writer; try again"};
  }

  RegionHeader& h = *impl->header;
  h.writer.pid.store(getpid(), std::memory_order_relaxed);
  h.writer.attach_count.fetch_add(1, std::memory_order_relaxed);
  h.writer.start_realtime_ns.store(realtime_ns(), std::memory_order_relaxed);
  pack_command(h.writer.command);
  h.liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
  h.liveness.max_publish_interval_ns.store(0, std::memory_order_relaxed);

  if (spec.lock_memory && mlock(impl->file.base(), impl->file.file_size()) != 0) {
    return errno_error(ErrorCode::system_error,
                       "cannot lock stream " + spec.name +
                           " in memory; raise RLIMIT_MEMLOCK (ulimit -l) or drop lock_memory",
                       errno);
  }

  if (spec.heartbeat_period.count() > 0) {
    WriterState* raw = impl.get();
    impl->heartbeat_thread = std::thread([raw, period = spec.heartbeat_period] {
      std::unique_lock lock(raw->heartbeat_mutex);
      while (!raw->heartbeat_stop_cv.wait_for(lock, period, [raw] { return raw->heartbeat_stop; })) {
        raw->header->liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
      }
    });
  }
  return Writer(std::move(impl));
}

Writer::Writer(std::unique_ptr<WriterState> impl) noexcept : impl_(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&&) noexcept = default;
Writer::~Writer() = default;

WriteStatus Writer::write(std::span<const std::byte> frame, std::int64_t stamp_ns,
                          std::int64_t receive_ns) noexcept {
  if (!impl_) return WriteStatus::closed;
  if (frame.size() > impl_->capacity) return WriteStatus::too_large;
  impl_->begin_write();
  ++impl_->loans_started;  // a loan still open is overtaken by this write
  std::memcpy(impl_->slot(impl_->last_seq + 1), frame.data(), frame.size());
  return publish(*impl_, frame.size(), stamp_ns, receive_ns);
}

Loan Writer::loan() noexcept {
  if (!impl_) return Loan(nullptr, {}, 0);
  impl_->begin_write();
  ++impl_->loans_started;
  return Loan(impl_.get(), {impl_->slot(impl_->last_seq + 1), impl_->capacity}, impl_->loans_started);
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
  meta.checksum.store(w.checksum ? XXH3_64bits(w.slot(seq), size) : 0, std::memory_order_relaxed);
  // The frame is complete: release it under its number, then make it the newest.
  meta.seq.store(seq, std::memory_order_release);
  Publication& pub = w.header->publication;
  pub.latest_seq.store(seq, std::memory_order_release);
  pub.futex_word.store(static_cast<std::uint32_t>(seq), std::memory_order_release);
  w.last_seq = seq;

  Liveness& live = w.header->liveness;
  if (w.last_publish_ns != 0 && now - w.last_publish_ns > w.max_interval_ns) {
    w.max_interval_ns = now - w.last_publish_ns;
    live.max_publish_interval_ns.store(w.max_interval_ns, std::memory_order_relaxed);
  }
  w.last_publish_ns = now;
  live.latest_publish_ns.store(now, std::memory_order_relaxed);
  live.heartbeat_ns.store(now, std::memory_order_relaxed);
  live.frames_published.fetch_add(1, std::memory_order_relaxed);

  // Dekker-style handshake with Reader::wait: either a sleeper sees the new frame before it
  // sleeps, or this load sees the sleeper and wakes it. No system call when nobody sleeps.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (w.file.wait_page()->sleepers.load(std::memory_order_relaxed) != 0) {
    futex_wake_all(&pub.futex_word);
  }
  return WriteStatus::ok;
}

}  // namespace

void Writer::heartbeat() noexcept {
  if (impl_) impl_->header->liveness.heartbeat_ns.store(monotonic_ns(), std::memory_order_relaxed);
}

const std::string& Writer::name() const noexcept { return impl_->name; }
std::uint64_t Writer::capacity() const noexcept { return impl_->capacity; }
const Layout& Writer::layout() const noexcept { return impl_->layout; }
std::uint64_t Writer::last_seq() const noexcept { return impl_->last_seq; }

Loan::Loan(Loan&& other) noexcept
    : writer_(std::exchange(other.writer_, nullptr)),
      bytes_(std::exchange(other.bytes_, {})),
      seq_(std::exchange(other.seq_, 0)) {}

Loan& Loan::operator=(Loan&& other) noexcept {
  writer_ = std::exchange(other.writer_, nullptr);
  bytes_ = std::exchange(other.bytes_, {});
  seq_ = std::exchange(other.seq_, 0);
  return *this;
}

WriteStatus Loan::commit(std::uint64_t size, std::int64_t stamp_ns, std::int64_t receive_ns) noexcept {
  if (writer_ == nullptr || writer_->loans_started != seq_) return WriteStatus::closed;
  const WriteStatus status = publish(*writer_, size, stamp_ns, receive_ns);
  if (status == WriteStatus::ok) {
    writer_ = nullptr;
    bytes_ = {};
  }
  return status;
}

}  // namespace sim
