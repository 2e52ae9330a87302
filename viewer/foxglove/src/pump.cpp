// SPDX-License-Identifier: Apache-2.0
#include "pump.hpp"

#include <algorithm>
#include <cstdio>

#include "foxglove_messages.hpp"
#include "sim/clock.hpp"

namespace sim::foxglove {
namespace {

using namespace std::chrono_literals;

// How often a stopping pump notices: the longest a reader sleeps in one wait.
constexpr auto kWaitSlice = 100ms;

void sleep_unless(const std::atomic<bool>& stopping, std::chrono::nanoseconds total) {
  const auto until = std::chrono::steady_clock::now() + total;
  while (!stopping.load(std::memory_order_relaxed) && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::min<std::chrono::nanoseconds>(
        kWaitSlice, until - std::chrono::steady_clock::now()));
  }
}

}  // namespace

Pump::Pump(std::string stream, std::uint32_t channel_id, Layout layout, PumpOptions options)
    : stream_(std::move(stream)),
      channel_id_(channel_id),
      layout_(layout),
      options_(options),
      thread_([this] { run(); }) {}

Pump::~Pump() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
}

void Pump::add(const std::shared_ptr<Subscriber>& subscriber) {
  std::lock_guard lock(subscribers_mutex_);
  subscribers_.push_back(subscriber);
}

std::size_t Pump::remove(const Subscriber* subscriber) {
  std::lock_guard lock(subscribers_mutex_);
  std::erase_if(subscribers_, [&](const std::weak_ptr<Subscriber>& w) {
    const auto s = w.lock();
    return !s || s.get() == subscriber;
  });
  return subscribers_.size();
}

std::size_t Pump::subscriber_count() {
  std::lock_guard lock(subscribers_mutex_);
  std::erase_if(subscribers_, [](const std::weak_ptr<Subscriber>& w) { return w.expired(); });
  return subscribers_.size();
}

void Pump::deliver(const std::shared_ptr<const Message>& message) {
  std::vector<std::shared_ptr<Subscriber>> targets;
  {
    std::lock_guard lock(subscribers_mutex_);
    for (const auto& w : subscribers_) {
      if (auto s = w.lock()) targets.push_back(std::move(s));
    }
  }
  for (const auto& s : targets) s->offer(message);
}

void Pump::run() {
  std::optional<Reader> reader;
  FrameEncoder encoder(layout_, options_.encode, frame_of(stream_, std::nullopt));
  std::uint64_t sensor_generation = 0;  // of the description `encoder` has the frame id from
  // Server::start refuses rates under kMinRateHz, whose interval would overflow.
  const auto min_interval =
      options_.max_rate_hz > 0 ? std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / options_.max_rate_hz))
                               : std::chrono::nanoseconds(0);
  bool reported = false;
  while (!stopping_.load(std::memory_order_relaxed)) {
    if (!reader) {
      auto opened = Reader::open(stream_, {.trust = options_.trust});
      if (!opened) {
        sleep_unless(stopping_, 500ms);  // the catalog unadvertises it if it stays gone
        continue;
      }
      reader.emplace(std::move(opened.value()));
    }
    const ReadStatus waited = reader->wait(kWaitSlice);
    if (waited == ReadStatus::region_invalid) {
      reader.reset();
      continue;
    }
    if (waited != ReadStatus::new_frame) continue;
    // Between the last unsubscribe and the reaper, a pump only waits: no encoding for nobody.
    if (subscriber_count() == 0) continue;
    const Borrow frame = reader->borrow();
    if (frame.status() != ReadStatus::new_frame) continue;
    // A stream recreated with another layout is a new channel; this pump only waits to end.
    if (!(frame.info().layout == layout_)) continue;
    // The writer described its sensor anew (or first): messages carry the sensor's frame, the
    // one its calibration and mounting name. Read only when the generation changes.
    if (frame.info().sensor_generation != sensor_generation) {
      sensor_generation = frame.info().sensor_generation;
      auto sensor = reader->sensor_info();
      encoder.set_frame_id(frame_of(stream_, sensor ? *sensor : std::nullopt));
    }

    auto message = std::make_shared<Message>();
    message->channel_id = channel_id_;
    message->timestamp_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(frame.info().stamp_ns, 0));
    message->seq = frame.info().seq;
    const auto error = encoder.encode(frame.bytes(), frame.info(), message->payload);
    // The writer may have started to overwrite the slot while we read it: drop that copy, the
    // next wait returns the newer frame.
    if (!frame.still_valid()) continue;
    if (error) {
      if (!reported) {
        std::fprintf(stderr, "sim_foxglove: %s: %s\n", stream_.c_str(), error->message.c_str());
        reported = true;
      }
      continue;
    }
    encoded_.fetch_add(1, std::memory_order_relaxed);
    deliver(message);
    if (min_interval.count() > 0) sleep_unless(stopping_, min_interval);
  }
}

}  // namespace sim::foxglove
