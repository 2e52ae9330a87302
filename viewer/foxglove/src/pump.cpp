// SPDX-License-Identifier: Apache-2.0
#include "pump.hpp"

#include <algorithm>
#include <cstdio>

#include "foxglove_messages.hpp"
#include "sim/clock.hpp"
#include "sim/wait_set.hpp"

namespace sim::foxglove {
namespace {

using namespace std::chrono_literals;

// The longest a runner sleeps in one wait (added and removed pumps and the destructor wake it
// at once, through its Wakeup).
constexpr auto kWaitSlice = 100ms;
// How often a pump tries again to open a stream it could not open (the catalog unadvertises
// it if it stays gone).
constexpr auto kReopenInterval = 500ms;

Pump::Clock::duration interval_of(double max_rate_hz) {
  // Server::start refuses rates under kMinRateHz, whose interval would overflow.
  if (max_rate_hz <= 0) return Pump::Clock::duration::zero();
  return std::chrono::duration_cast<Pump::Clock::duration>(
      std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / max_rate_hz)));
}

}  // namespace

Pump::Pump(std::string stream, std::uint32_t channel_id, Layout layout, PumpOptions options)
    : stream_(std::move(stream)),
      channel_id_(channel_id),
      layout_(layout),
      options_(options),
      min_interval_(interval_of(options.max_rate_hz)),
      encoder_(layout, options.encode, frame_of(stream_, std::nullopt)) {}

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

std::shared_ptr<Message> Pump::reusable_message() {
  for (const auto& spare : spares_) {
    if (spare.use_count() == 1) {
      // Every client let go of it (each with a releasing decrement): their reads of its bytes
      // happen before the encoder writes them again.
      std::atomic_thread_fence(std::memory_order_acquire);
      return spare;
    }
  }
  auto message = std::make_shared<Message>();
  if (spares_.size() < kSpareMessages) spares_.push_back(message);
  return message;
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

Reader* Pump::reader(Clock::time_point now) {
  if (!reader_ && now >= next_open_) {
    auto opened = Reader::open(stream_, {.trust = options_.trust});
    if (opened) {
      reader_.emplace(std::move(opened.value()));
    } else {
      next_open_ = now + kReopenInterval;
    }
  }
  return reader_ ? &*reader_ : nullptr;
}

Pump::Clock::time_point Pump::next_wait(Clock::time_point now) const {
  if (!reader_) return std::max(now, next_open_);
  return std::max(now, next_due_);
}

bool Pump::take_frame(Clock::time_point now) {
  const Borrow frame = reader_->borrow();  // takes the frame even if nobody wants it any more
  if (frame.status() == ReadStatus::region_invalid) {
    reader_.reset();
    return false;
  }
  if (frame.status() != ReadStatus::new_frame) return true;
  // Between the last unsubscribe and the reaper, a pump only takes frames: no encoding for nobody.
  if (subscriber_count() == 0) return true;
  // A stream recreated with another layout is a new channel; this pump only waits to end.
  if (!(frame.info().layout == layout_)) return true;
  // The writer described its sensor anew (or first): messages carry the sensor's frame, the
  // one its calibration and mounting name. Read only when the generation changes.
  if (frame.info().sensor_generation != sensor_generation_) {
    // Review turn 4 M6: a description that cannot be read now (its writer stopped mid-update)
    // leaves the frame id as it was; the next frame looks again.
    if (auto sensor = reader_->sensor_info()) {
      sensor_generation_ = frame.info().sensor_generation;
      encoder_.set_frame_id(frame_of(stream_, *sensor));
    }
  }

  const std::shared_ptr<Message> message = reusable_message();
  message->channel_id = channel_id_;
  message->timestamp_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(frame.info().stamp_ns, 0));
  message->seq = frame.info().seq;
  const auto error = encoder_.encode(frame.bytes(), frame.info(), message->payload);
  // The writer may have started to overwrite the slot while we read it: drop that copy, the
  // next wait returns the newer frame.
  if (!frame.still_valid()) return true;
  if (error) {
    if (!reported_) {
      std::fprintf(stderr, "sim_foxglove: %s: %s\n", stream_.c_str(), error->message.c_str());
      reported_ = true;
    }
    return true;
  }
  encoded_.fetch_add(1, std::memory_order_relaxed);
  deliver(message);
  if (min_interval_ > Clock::duration::zero()) next_due_ = now + min_interval_;
  return true;
}

PumpRunner::PumpRunner() : thread_([this] { run(); }) {}

PumpRunner::~PumpRunner() {
  stopping_.store(true);
  wakeup_.notify();
  if (thread_.joinable()) thread_.join();
}

bool PumpRunner::add(const std::shared_ptr<Pump>& pump) {
  {
    std::lock_guard lock(mutex_);
    if (pumps_.size() >= WaitSet::kMaxReaders) return false;
    pumps_.push_back(pump);
    changed_ = true;
  }
  wakeup_.notify();  // the new subscriber's first frame goes out without waiting for a slice
  return true;
}

void PumpRunner::remove(const Pump* pump) {
  {
    std::lock_guard lock(mutex_);
    if (std::erase_if(pumps_, [&](const auto& p) { return p.get() == pump; }) == 0) return;
    changed_ = true;
  }
  wakeup_.notify();
}

std::size_t PumpRunner::size() const {
  std::lock_guard lock(mutex_);
  return pumps_.size();
}

void PumpRunner::run() {
  std::vector<std::shared_ptr<Pump>> pumps;  // this thread's copy of pumps_
  std::vector<Pump*> waiting;                // the pumps whose readers are in `set`, by index
  std::vector<Pump*> wanted;
  // A set of no readers yet that ends its waits when add(), remove() or the destructor notify.
  auto empty_set = [this] {
    WaitSet set;
    set.watch(wakeup_);
    return set;
  };
  WaitSet set = empty_set();
  while (!stopping_.load(std::memory_order_relaxed)) {
    {
      std::lock_guard lock(mutex_);
      if (changed_) {
        set = empty_set();  // it may name readers of pumps let go now: built anew below
        waiting.clear();
        pumps = pumps_;
        changed_ = false;
      }
    }
    // The readers worth waiting on now; the others (not open, or held back by --max-rate)
    // join when their time comes.
    auto now = Pump::Clock::now();
    auto wake = now + kWaitSlice;
    wanted.clear();
    for (const auto& pump : pumps) {
      if (pump->next_wait(now) <= now && pump->reader(now) != nullptr) {
        wanted.push_back(pump.get());
        continue;
      }
      wake = std::min(wake, std::max(pump->next_wait(now), now + 1ms));
    }
    if (wanted != waiting) {
      set = empty_set();
      for (Pump* pump : wanted) (void)set.add(*pump->reader(now));  // at most kMaxReaders
      waiting = wanted;
    }
    if (!set.wait(wake - now)) continue;
    now = Pump::Clock::now();
    bool reader_closed = false;
    for (std::size_t i = 0; i < waiting.size(); ++i) {
      if (set.ready(i)) reader_closed |= !waiting[i]->take_frame(now);
    }
    if (reader_closed) {  // the set names a closed reader: build it anew
      waiting.clear();
      set = empty_set();
    }
  }
}

}  // namespace sim::foxglove
