// SPDX-License-Identifier: Apache-2.0
// The one writer of a stream. It owns the region's writer lock for its whole life, fills the slot
// readers are not reading, and publishes it with one release store; it never waits for readers.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

#include "sim/layout.hpp"
#include "sim/result.hpp"
#include "sim/clock_status.hpp"
#include "sim/sensor_info.hpp"
#include "sim/span.hpp"

namespace sim {

struct StreamSpec {
  std::string name;               // "/lidar_top": a slash, then 1–200 of [A-Za-z0-9_.-]
  std::uint64_t capacity = 0;     // bytes per slot; 0 takes layout.min_capacity()
  Layout layout = Layout::raw();
  bool checksum = false;          // XXH3-64 over each frame, verified by readers
  // File mode of the region: 0600, or 0640 to let the file's group read (0644: everyone). Nobody
  // but the owner may ever write it: modes with group or other write bits are refused.
  std::uint32_t mode = 0600;
  bool lock_memory = false;       // mlock the region so frames never page-fault
  // Refresh the heartbeat from a background thread while no frame is written, so readers can
  // tell an idle writer from a dead one. Zero: the heartbeat moves only with published frames.
  std::chrono::milliseconds heartbeat_period{0};
  // What the stream says about its sensor (frame, mounting, calibration, identity, time base).
  // Empty: nothing, and a description a previous writer of the region left is removed. A
  // description sensor_info_problem() finds fault with makes create() fail with its sentence.
  std::optional<SensorInfo> sensor{};
};

enum class WriteStatus {
  ok,
  too_large,  // the frame is larger than the stream's capacity: nothing was published
  closed,     // the writer was moved from, or the loan was already committed or given up
  loan_open,  // a loan of this writer is still open: commit or drop it first
};

const char* to_string(WriteStatus status) noexcept;

// The bytes of shared memory (/dev/shm) a stream of `capacity` bytes per frame takes: its two
// slots, page rounded, and two pages of header. For budgets (sim_play --max-shm).
std::uint64_t region_size(std::uint64_t capacity) noexcept;

class Writer;
namespace detail {
struct WriterState;
}

// A writable view of the back slot, so a driver decodes straight into shared memory.
// Committing publishes it; dropping it uncommitted publishes nothing. Move-only, and at most one
// per writer at a time: while it is open, the writer hands out no other view of that slot.
// A Loan must not outlive its Writer.
class Loan {
 public:
  Loan() noexcept = default;  // empty: valid() is false, no bytes
  Loan(Loan&& other) noexcept;
  Loan& operator=(Loan&& other) noexcept;
  Loan(const Loan&) = delete;
  Loan& operator=(const Loan&) = delete;
  ~Loan();

  span<std::byte> bytes() const noexcept { return bytes_; }
  template <typename T>
  span<T> as() const noexcept {
    static_assert(std::is_trivially_copyable_v<T>, "only plain data can live in shared memory");
    return {reinterpret_cast<T*>(bytes_.data()), bytes_.size() / sizeof(T)};
  }
  // False for a moved-from or committed loan, and for the empty loan loan() returns while
  // another loan is open.
  bool valid() const noexcept { return writer_ != nullptr; }

  // Publishes the first `size` bytes with the sensor time of the frame and, optionally, the
  // host time its first data arrived (both CLOCK_REALTIME, ns; see FrameInfo). Ends the loan
  // whatever the outcome, so it is called on an rvalue: std::move(loan).commit(size, stamp).
  [[nodiscard]] WriteStatus commit(std::uint64_t size, std::int64_t stamp_ns,
                                   std::int64_t receive_ns = 0) && noexcept;

 private:
  friend class Writer;
  Loan(detail::WriterState* writer, span<std::byte> bytes) noexcept
      : writer_(writer), bytes_(bytes) {}
  void release() noexcept;
  detail::WriterState* writer_ = nullptr;  // stays put when the Writer handle is moved
  detail::Bytes<std::byte> bytes_;
};

class Writer {
 public:
  // Creates the stream, or takes over an existing region of the same layout and capacity
  // (continuing its sequence numbers), or replaces one whose layout changed. Refused while
  // another live writer holds the stream.
  static Expected<Writer> create(const StreamSpec& spec);

  Writer(Writer&& other) noexcept;
  Writer& operator=(Writer&& other) noexcept;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  ~Writer();

  // Copies one frame in and publishes it (stamps as in Loan::commit). Refused (loan_open) while a
  // loan is open, which would otherwise still be writing into the slot this frame goes to.
  [[nodiscard]] WriteStatus write(span<const std::byte> frame, std::int64_t stamp_ns,
                                  std::int64_t receive_ns = 0) noexcept {
    return write(frame.data(), frame.size(), stamp_ns, receive_ns);
  }
  template <typename T>
  [[nodiscard]] WriteStatus write(span<const T> items, std::int64_t stamp_ns,
                                  std::int64_t receive_ns = 0) noexcept {
    static_assert(std::is_trivially_copyable_v<T>);
    return write(sim::as_bytes(items), stamp_ns, receive_ns);
  }
  // The same with the frame as a pointer and its size (the exported function, so C++17 and
  // C++20 programs call one function).
  [[nodiscard]] WriteStatus write(const std::byte* frame, std::size_t size, std::int64_t stamp_ns,
                                  std::int64_t receive_ns = 0) noexcept;

  // The back slot, to fill in place. At most one loan at a time: while one is open this returns
  // an empty loan (valid() false, no bytes).
  [[nodiscard]] Loan loan() noexcept;

  // Tells readers the writer is alive without publishing a frame.
  void heartbeat() noexcept;

  // Replaces the stream's sensor description (a recalibration, a remount): readers see it with
  // their next Reader::sensor_info() and the frames published from now on carry a new
  // FrameInfo::sensor_generation. Refused with the sentence of sensor_info_problem(). Costs a
  // copy of about 1 KiB into the header page; publishing frames costs nothing more for it.
  Expected<void> set_sensor_info(const SensorInfo& info);

  // Replaces the stream's clock record (sim/clock_status.hpp; a driver's clock check, about once
  // a second): readers see it with their next Reader::clock() and a new
  // FrameInfo::clock_generation; the frames published from now on carry `clock.stamps` as their
  // FrameInfo::stamp_clock. Refused with the sentence of clock_status_problem(). May be called
  // from another thread than the one publishing, by one thread at a time. Costs a copy of
  // 400 bytes into the header page; publishing frames costs nothing more for it.
  Expected<void> set_clock(const ClockStatus& clock);

  // Keeps the region mapped while held, even after this Writer is gone (its lock is released
  // all the same): for bindings whose views into a loan may outlive the writer. Null if moved from.
  std::shared_ptr<const void> mapping() const noexcept;

  const std::string& name() const noexcept;
  std::uint64_t capacity() const noexcept;
  const Layout& layout() const noexcept;
  std::uint64_t last_seq() const noexcept;  // sequence number of the newest published frame

 private:
  explicit Writer(std::unique_ptr<detail::WriterState> state) noexcept;
  std::unique_ptr<detail::WriterState> impl_;
};

}  // namespace sim
