// SPDX-License-Identifier: Apache-2.0
// One subscribed channel: a thread with its own SIM reader that waits for each new frame,
// encodes it once straight from the borrowed slot and hands the same bytes to every subscriber.
// It exists only while someone subscribes (no work for streams nobody watches), it never blocks
// the writer (borrow, then check the slot was not overwritten), and it hands over only the newest
// message: subscribers keep one pending message each, never a queue.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "encoder.hpp"
#include "sim/reader.hpp"

namespace sim::foxglove {

struct Message {
  std::uint32_t channel_id = 0;
  std::uint64_t timestamp_ns = 0;  // the frame's sensor stamp
  std::uint64_t seq = 0;
  std::vector<std::byte> payload;
};

// Whoever takes a channel's messages (a WebSocket client). Called on the pump's thread; must
// return quickly and keep at most the newest message.
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
  Pump(std::string stream, std::uint32_t channel_id, Layout layout, PumpOptions options);
  Pump(const Pump&) = delete;
  Pump& operator=(const Pump&) = delete;
  ~Pump();  // stops and joins the thread

  void add(const std::shared_ptr<Subscriber>& subscriber);
  // Removes the subscriber; returns how many are left.
  std::size_t remove(const Subscriber* subscriber);
  std::size_t subscriber_count();

  // Frames encoded and frames the slot changed under (both only grow).
  std::uint64_t encoded() const noexcept { return encoded_.load(std::memory_order_relaxed); }

 private:
  void run();
  void deliver(const std::shared_ptr<const Message>& message);

  const std::string stream_;
  const std::uint32_t channel_id_;
  const Layout layout_;
  const PumpOptions options_;

  std::mutex subscribers_mutex_;
  std::vector<std::weak_ptr<Subscriber>> subscribers_;

  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> encoded_{0};
  std::thread thread_;
};

}  // namespace sim::foxglove
