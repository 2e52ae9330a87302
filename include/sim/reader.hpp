// SPDX-License-Identifier: Apache-2.0
// A reader of one stream. Any number of readers, in any processes; they never wait for each
// other or for the writer, and they never deliver a torn frame (see docs/protocol.md).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim {

struct FrameInfo {
  std::uint64_t seq = 0;         // 1 for the first frame ever published on the stream
  std::int64_t stamp_ns = 0;     // sensor time of the frame (CLOCK_REALTIME, ns)
  std::int64_t publish_ns = 0;   // when the writer published it (CLOCK_MONOTONIC, ns)
  std::int64_t receive_ns = 0;   // when the host received the frame's first data (CLOCK_REALTIME,
                                 // ns), kept beside the sensor's own stamp; 0 if not given
  std::uint64_t size = 0;        // bytes
  Layout layout{};
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

struct ReaderOptions {
  // A frame older than this (by its publish time) makes an idle stream "stale". Zero: never.
  std::chrono::nanoseconds stale_after{0};
  // Verify the writer's per-frame checksum when the stream has one.
  bool verify_checksum = true;
  // Readers refuse a region owned by another user unless told to trust it (group streams).
  bool accept_other_owner = false;
};

struct ReaderStats {
  std::uint64_t frames = 0;              // frames delivered
  std::uint64_t skipped = 0;             // frames published but replaced before this reader came
  std::uint64_t overruns = 0;            // copies invalidated by the writer and retried
  std::uint64_t checksum_failures = 0;
  std::uint64_t reopens = 0;             // times the region was replaced and reopened
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
  std::int64_t writer_start_realtime_ns = 0;
  std::int32_t writer_pid = 0;
  std::string writer_command;               // the writer's process name
  bool writer_alive = false;
  std::uint32_t sleeping_readers = 0;
};

class Reader;

// A published frame read in place. It can be overwritten at any time once the writer has
// published two more frames; check still_valid() after using the bytes and discard them if false.
// A Borrow must not outlive its Reader.
class Borrow {
 public:
  ReadStatus status() const noexcept { return status_; }
  const FrameInfo& info() const noexcept { return info_; }
  std::span<const std::byte> bytes() const noexcept { return bytes_; }
  template <typename T>
  std::span<const T> as() const noexcept {
    static_assert(std::is_trivially_copyable_v<T>);
    return {reinterpret_cast<const T*>(bytes_.data()), bytes_.size() / sizeof(T)};
  }
  // True when the writer has not begun to overwrite the slot since it was borrowed.
  bool still_valid() const noexcept;

 private:
  friend class Reader;
  ReadStatus status_ = ReadStatus::no_new_frame;
  FrameInfo info_{};
  std::span<const std::byte> bytes_{};
  const void* slot_seq_ = nullptr;  // the slot's sequence word in shared memory
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
  ReadStatus read(std::span<std::byte> out, FrameInfo& info) noexcept;
  // Sleeps until a frame newer than the last one returned is published, or the timeout passes.
  ReadStatus wait(std::chrono::nanoseconds timeout) noexcept;
  // wait() then read().
  ReadStatus read_next(std::span<std::byte> out, FrameInfo& info,
                       std::chrono::nanoseconds timeout) noexcept;
  // The newest frame in place, if it is newer than the last one returned.
  Borrow borrow() noexcept;

  // Whether a process holds the stream's writer lock (one system call).
  bool writer_alive() noexcept;
  // Time since the newest frame was published, or -1 ns before the first frame.
  std::chrono::nanoseconds newest_age() const noexcept;

  const std::string& name() const noexcept;
  std::uint64_t capacity() const noexcept;
  const Layout& layout() const noexcept;
  bool checksum() const noexcept;
  ReaderStats stats() const noexcept;
  StreamStatus status() noexcept;

  struct Impl;

 private:
  explicit Reader(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// Names of every SIM stream on this machine ("/lidar_top", …), sorted.
std::vector<std::string> list_streams();
// The diagnostics of one stream without keeping it open.
Expected<StreamStatus> inspect(std::string_view name);
// Removes a stream's region. Refused while its writer is alive unless `force`.
// Readers that have it open keep their mapping until they close it.
std::optional<Error> destroy(std::string_view name, bool force = false);

}  // namespace sim
