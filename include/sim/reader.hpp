// SPDX-License-Identifier: Apache-2.0
// A reader of one stream. Any number of readers, in any processes; they never wait for each
// other or for the writer, and they never deliver a torn frame (see docs/protocol.md).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <ratio>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "sim/layout.hpp"
#include "sim/result.hpp"
#include "sim/clock_status.hpp"
#include "sim/sensor_info.hpp"
#include "sim/span.hpp"

namespace sim {

struct FrameInfo {
  std::uint64_t seq = 0;         // 1 for the first frame ever published on the stream
  std::int64_t stamp_ns = 0;     // sensor time of the frame (CLOCK_REALTIME, ns)
  std::int64_t publish_ns = 0;   // when the writer published it (CLOCK_MONOTONIC, ns)
  std::int64_t receive_ns = 0;   // when the host received the frame's first data (CLOCK_REALTIME,
                                 // ns), kept beside the sensor's own stamp; 0 if not given
  std::uint64_t size = 0;        // bytes
  Layout layout{};
  // The generation of the stream's sensor description when the frame was read: 0 when the stream
  // has none, else a number that changes every time the writer sets one (Writer::set_sensor_info,
  // a new writer). Compare it with the last one seen to know when to call Reader::sensor_info().
  std::uint64_t sensor_generation = 0;
  // Likewise for the stream's clock record (Writer::set_clock, about once a second from a
  // driver): compare it with the last one seen to know when to call Reader::clock().
  std::uint64_t clock_generation = 0;
  // Which clock stamp_ns is in (the sensor's, corrected for TAI, or the host's at arrival), as
  // the writer's clock record said when it published the frame; unknown from older writers.
  StampClock stamp_clock = StampClock::unknown;
};

enum class ReadStatus {
  new_frame,          // a frame newer than the last one this reader returned
  no_new_frame,       // nothing newer (or, from wait, the timeout passed)
  writer_gone,        // nothing newer, and no process holds the writer's lock
  stale,              // nothing newer, and the newest frame is older than stale_after
  checksum_mismatch,  // the newest frame failed its checksum; it was not delivered
  buffer_too_small,   // the caller's buffer cannot hold the newest frame; nothing was copied
  overrun,            // the writer overwrote the frame faster than it could be copied (retried)
  region_invalid,     // the region no longer passes validation; reopen or give up
};

const char* to_string(ReadStatus status) noexcept;

// Whose regions a reader accepts. A region is a file anyone with write access to /dev/shm could
// have created under the name first; the trust says which creator is the real writer.
// Default (nothing set): only regions of the reader's own effective user.
struct Trust {
  std::optional<std::uint32_t> owner_uid;  // the region must belong to this user
  std::optional<std::uint32_t> group_gid;  // the region must belong to this group: every member
                                           // of the group is then trusted to be the writer
  bool anyone = false;  // any owner at all: for looking (sim_ls), never for frames you act on

  static Trust user(std::uint32_t uid) { return {uid, std::nullopt, false}; }
  static Trust group(std::uint32_t gid) { return {std::nullopt, gid, false}; }
  static Trust any_owner() { return {std::nullopt, std::nullopt, true}; }
  // From a tool's --trust-owner / --trust-group: user and group names or numeric ids; an empty
  // string leaves that part unset. Fails with a sentence for an unknown name.
  static Expected<Trust> parse(std::string_view owner, std::string_view group);
  // "user alice", "group sensors", "user alice and group sensors", "this user".
  std::string describe() const;
};

// How Reader::wait waits for the next frame (docs/protocol.md, "Waiting").
enum class WaitMode {
  block,     // sleep on the futex until the writer publishes: no CPU while idle
  poll,      // spin on the newest frame number: lowest latency, one whole core while waiting
  adaptive,  // sleep until shortly before the writer's next expected publish, then spin briefly;
             // a stream without a steady period (or a silent one) is waited for as in `block`
};

struct ReaderOptions {
  // A frame older than this (by its publish time) makes an idle stream "stale". Zero: never.
  std::chrono::nanoseconds stale_after{0};
  // Verify the writer's per-frame checksum when the stream has one.
  bool verify_checksum = true;
  // Whose regions to accept (see Trust); a region of anyone else is refused with a sentence that
  // names its actual owner.
  Trust trust{};
  // How wait() (and read_next) wait; see WaitMode.
  WaitMode wait_mode = WaitMode::block;
};

// A wait that never times out: Reader::wait(sim::kForever).
inline constexpr std::chrono::nanoseconds kForever = std::chrono::nanoseconds::max();

// `timeout` in nanoseconds, clamped to what nanoseconds can hold (hours(100000000) is "forever",
// not an overflow into the past).
template <typename Rep, typename Period>
constexpr std::chrono::nanoseconds saturating_nanoseconds(std::chrono::duration<Rep, Period> timeout) {
  using Unit = std::chrono::duration<Rep, Period>;
  if constexpr (std::ratio_less_equal_v<Period, std::nano>) {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
  } else {
    constexpr Unit kMaxInUnit = std::chrono::duration_cast<Unit>(std::chrono::nanoseconds::max());
    if (timeout >= kMaxInUnit) return std::chrono::nanoseconds::max();
    if (timeout <= -kMaxInUnit) return std::chrono::nanoseconds::min();
    return std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
  }
}

struct ReaderStats {
  std::uint64_t frames = 0;              // frames delivered
  std::uint64_t skipped = 0;             // frames published but replaced before this reader came
  std::uint64_t overruns = 0;            // copies invalidated by the writer and retried
  std::uint64_t checksum_failures = 0;
  std::uint64_t reopens = 0;             // times the region was replaced and reopened
  std::uint64_t spins = 0;               // adaptive/poll waits that spun (WaitMode)
  std::uint64_t caught_spinning = 0;     // frames that arrived while this reader spun
  std::int64_t spin_ns = 0;              // time spent spinning: this reader's busy CPU in wait()
};

// Diagnostics the writer keeps in the region header; sim_ls shows them.
struct StreamStatus {
  std::string name;
  Layout layout{};
  std::uint64_t capacity = 0;
  bool checksum = false;
  std::uint64_t frames_published = 0;
  std::uint64_t latest_seq = 0;
  std::int64_t latest_publish_ns = 0;       // CLOCK_MONOTONIC; 0 before the first frame
  std::int64_t heartbeat_ns = 0;            // CLOCK_MONOTONIC
  std::int64_t max_publish_interval_ns = 0;
  // The current writer's publish period and its typical deviation, smoothed over its recent frames
  // on CLOCK_MONOTONIC (0 until it has published twice; frames of earlier writers do not count).
  std::int64_t period_ns = 0;
  std::int64_t jitter_ns = 0;
  std::uint64_t frames_this_writer = 0;
  std::int64_t writer_start_realtime_ns = 0;
  std::int32_t writer_pid = 0;
  // The writer's program name ("sim_replay_video"), kept after it died; writers that predate
  // the whole name give the kernel's 15 characters of it ("sim_replay_vide").
  std::string writer_command;
  bool writer_alive = false;
  std::uint32_t sleeping_readers = 0;  // the owner's readers asleep in wait()
  std::uint32_t owner_uid = 0;         // who owns the region file
  std::uint32_t owner_gid = 0;
  std::uint32_t mode = 0;              // its permission bits (0600, 0640)
  std::optional<SensorInfo> sensor{};  // the stream's sensor description, if it has a valid one
  std::string sensor_problem{};        // why `sensor` is empty though the stream has one (damaged)
  std::uint64_t sensor_generation = 0; // as FrameInfo::sensor_generation
  std::optional<ClockStatus> clock{};  // the stream's clock record, if it has a valid one
  std::string clock_problem{};         // why `clock` is empty though the stream has one (damaged)
  std::uint64_t clock_generation = 0;  // as FrameInfo::clock_generation

  // Frames per second over the current writer's recent frames; 0 when it has not published twice
  // or has not published for three periods (it stopped).
  double rate_hz(std::int64_t now_monotonic_ns) const noexcept;
};

class Reader;
namespace detail {
struct ReaderWaitAccess;  // WaitSet's view of a reader's wake-up machinery (sim/reader_wait.hpp)
}

// A published frame read in place. It can be overwritten at any time once the writer has
// published two more frames; check still_valid() after using the bytes and discard them if false.
// A Borrow keeps the region it points into mapped, so it stays safe to use and to ask whatever
// happens to the stream meanwhile (replaced, removed) and even after its Reader is gone.
class Borrow {
 public:
  ReadStatus status() const noexcept { return status_; }
  const FrameInfo& info() const noexcept { return info_; }
  span<const std::byte> bytes() const noexcept { return bytes_; }
  template <typename T>
  span<const T> as() const noexcept {
    static_assert(std::is_trivially_copyable_v<T>);
    return {reinterpret_cast<const T*>(bytes_.data()), bytes_.size() / sizeof(T)};
  }
  // True when the writer has not begun to overwrite the slot since it was borrowed.
  [[nodiscard]] bool still_valid() const noexcept;

 private:
  friend class Reader;
  ReadStatus status_ = ReadStatus::no_new_frame;
  FrameInfo info_{};
  detail::Bytes<const std::byte> bytes_{};
  const void* slot_seq_ = nullptr;        // the slot's sequence word in shared memory
  std::shared_ptr<const void> mapping_;  // keeps the region mapped while the Borrow lives
};

class Reader {
 public:
  static Expected<Reader> open(std::string_view name, const ReaderOptions& options = {});

  Reader(Reader&& other) noexcept;
  Reader& operator=(Reader&& other) noexcept;
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  ~Reader();

  // Copies the newest frame into `out` if it is newer than the last one returned.
  [[nodiscard]] ReadStatus read(span<std::byte> out, FrameInfo& info) noexcept {
    return read(out.data(), out.size(), info);
  }
  // The same with the buffer as a pointer and its size (what the library exports, so C++17 and
  // C++20 programs call one function).
  [[nodiscard]] ReadStatus read(std::byte* out, std::size_t size, FrameInfo& info) noexcept;
  // Sleeps until a frame that read() or borrow() can deliver is published, or the timeout passes
  // (kForever: no timeout). Returns new_frame only when there is such a frame.
  [[nodiscard]] ReadStatus wait(std::chrono::nanoseconds timeout) noexcept;
  template <typename Rep, typename Period>
  [[nodiscard]] ReadStatus wait(std::chrono::duration<Rep, Period> timeout) noexcept {
    return wait(saturating_nanoseconds(timeout));
  }
  // wait() then read().
  [[nodiscard]] ReadStatus read_next(span<std::byte> out, FrameInfo& info,
                                     std::chrono::nanoseconds timeout) noexcept {
    return read_next(out.data(), out.size(), info, timeout);
  }
  template <typename Rep, typename Period>
  [[nodiscard]] ReadStatus read_next(span<std::byte> out, FrameInfo& info,
                                     std::chrono::duration<Rep, Period> timeout) noexcept {
    return read_next(out, info, saturating_nanoseconds(timeout));
  }
  // The same with the buffer as a pointer and its size (the exported function).
  [[nodiscard]] ReadStatus read_next(std::byte* out, std::size_t size, FrameInfo& info,
                                     std::chrono::nanoseconds timeout) noexcept;
  // The newest frame in place, if it is newer than the last one returned.
  [[nodiscard]] Borrow borrow() noexcept;

  // Changes how wait() waits (ReaderOptions::wait_mode).
  void set_wait_mode(WaitMode mode) noexcept;

  // Whether a process holds the stream's writer lock (one system call).
  [[nodiscard]] bool writer_alive() noexcept;
  // Time since the newest frame was published, or -1 ns before the first frame.
  std::chrono::nanoseconds newest_age() const noexcept;

  const std::string& name() const noexcept;
  std::uint64_t capacity() const noexcept;
  const Layout& layout() const noexcept;
  bool checksum() const noexcept;
  ReaderStats stats() const noexcept;
  StreamStatus status() noexcept;
  // The stream's sensor description as its writer set it last: nullopt when it has none; an
  // Error (one sentence) when the description in the region is damaged, which leaves frames
  // flowing. Copies about 1 KiB and allocates: call it when FrameInfo::sensor_generation changed,
  // not per frame.
  Expected<std::optional<SensorInfo>> sensor_info() const;
  // The stream's clock record as its writer set it last (sim/clock_status.hpp): nullopt when it
  // has none (yet); an Error (one sentence) when the record in the region is damaged, which
  // leaves frames flowing. Call it when FrameInfo::clock_generation changed, not per frame.
  Expected<std::optional<ClockStatus>> clock() const;

  struct Impl;

 private:
  friend struct detail::ReaderWaitAccess;
  explicit Reader(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// Names of every SIM stream on this machine ("/lidar_top", …), sorted.
std::vector<std::string> list_streams();
// The diagnostics of one stream without keeping it open.
Expected<StreamStatus> inspect(std::string_view name);
// Removes a stream's region. Refused while its writer is alive unless `force`. A writer starting
// or restarting at the same moment either keeps the region (removal is refused) or finds the name
// free and creates a new one: it never goes on writing into a removed file (unless `force`).
// Readers that have it open keep their mapping until they close it.
Expected<void> destroy(std::string_view name, bool force = false);

}  // namespace sim
