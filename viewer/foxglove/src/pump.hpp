// SPDX-License-Identifier: Apache-2.0
// Subscribed channels and the threads that feed them. A Pump is one subscribed channel: its own
// SIM reader, encoder and subscribers; it encodes each new frame once straight from the borrowed
// slot and hands the same bytes to every subscriber. It has no thread: a PumpRunner sleeps on
// the readers of up to 128 pumps at once (a sim::WaitSet) and runs the pump of each stream that
// has a new frame, so 300 subscribed channels cost 3 threads, not 300 (review L4).
// A pump exists only while someone subscribes (no work for streams nobody watches), it never
// blocks the writer (borrow, then check the slot was not overwritten), and it hands over only
// the newest message: subscribers keep one pending message each, never a queue.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "encoder.hpp"
#include "sim/reader.hpp"
#include "sim/wait_set.hpp"

namespace sim::foxglove {

struct Message {
  std::uint32_t channel_id = 0;
  std::uint64_t timestamp_ns = 0;  // the frame's sensor stamp
  std::uint64_t seq = 0;
  std::vector<std::byte> payload;
};

// Whoever takes a channel's messages (a WebSocket client). Called on a runner's thread; must
// return quickly (never wait for the network) and keep at most the newest message.
class Subscriber {
 public:
  virtual ~Subscriber() = default;
  virtual void offer(std::shared_ptr<const Message> message) = 0;
};

struct PumpOptions {
  EncodeOptions encode;
  double max_rate_hz = 0;  // 0: every frame
  Trust trust{};           // whose regions to read
};

class Pump {
 public:
  using Clock = std::chrono::steady_clock;

  Pump(std::string stream, std::uint32_t channel_id, Layout layout, PumpOptions options);
  Pump(const Pump&) = delete;
  Pump& operator=(const Pump&) = delete;

  void add(const std::shared_ptr<Subscriber>& subscriber);
  // Removes the subscriber; returns how many are left.
  std::size_t remove(const Subscriber* subscriber);
  std::size_t subscriber_count();

  // Frames encoded (only grows).
  std::uint64_t encoded() const noexcept { return encoded_.load(std::memory_order_relaxed); }

  // --- Only from the thread of the runner that holds the pump. ---
  // The open reader, or null while the stream cannot be opened (tried again every 500 ms).
  Reader* reader(Clock::time_point now);
  // When the reader is worth waiting on: at once, or when --max-rate lets the next message go,
  // or when the stream may be opened again.
  Clock::time_point next_wait(Clock::time_point now) const;
  // Takes the reader's new frame: encodes it and hands it to every subscriber. False when the
  // reader had to be closed (its region became invalid); the runner then waits without it.
  bool take_frame(Clock::time_point now);

 private:
  // A message to encode the next frame into: a spare no client holds any more (its bytes'
  // memory is reused, so a frame of megabytes costs no allocation while clients keep up), else
  // a new one.
  std::shared_ptr<Message> reusable_message();
  void deliver(const std::shared_ptr<const Message>& message);

  const std::string stream_;
  const std::uint32_t channel_id_;
  const Layout layout_;
  const PumpOptions options_;
  const Clock::duration min_interval_;  // between two messages (--max-rate); 0: none

  std::mutex subscribers_mutex_;
  std::vector<std::weak_ptr<Subscriber>> subscribers_;
  std::atomic<std::uint64_t> encoded_{0};

  // The runner thread's.
  std::optional<Reader> reader_;
  Clock::time_point next_open_{};
  Clock::time_point next_due_{};
  FrameEncoder encoder_;
  std::uint64_t sensor_generation_ = 0;  // of the description `encoder_` has the frame id from
  bool reported_ = false;
  std::vector<std::shared_ptr<Message>> spares_;  // at most kSpareMessages
  static constexpr std::size_t kSpareMessages = 3;
};

// One thread that feeds up to WaitSet::kMaxReaders pumps. It sleeps on the readers of all of
// them at once and, when any has a new frame, runs those pumps. A pump held back by --max-rate
// is left out of the wait until its next message may go, so its newest frame then is sent (as
// a sleeping pump thread did) without the runner spinning on it meanwhile.
class PumpRunner {
 public:
  PumpRunner();
  PumpRunner(const PumpRunner&) = delete;
  PumpRunner& operator=(const PumpRunner&) = delete;
  ~PumpRunner();  // stops and joins the thread

  // False when the runner already feeds as many pumps as one wait can hold.
  bool add(const std::shared_ptr<Pump>& pump);
  // The runner stops using the pump at its next turn (it is woken for it).
  void remove(const Pump* pump);
  std::size_t size() const;

 private:
  void run();

  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Pump>> pumps_;
  bool changed_ = false;
  std::atomic<bool> stopping_{false};
  Wakeup wakeup_;      // ends the thread's wait when pumps_ changes or the runner stops
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace sim::foxglove
