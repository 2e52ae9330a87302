// SPDX-License-Identifier: Apache-2.0
#include "catalog.hpp"

#include <algorithm>

#include "sim/clock.hpp"

namespace sim::foxglove {
namespace {

// A rate needs a window long enough to hold a few frames of a 10 Hz LiDAR.
constexpr std::int64_t kRateWindowNs = 1'000'000'000;

}  // namespace

Catalog::Catalog(std::vector<std::string> only, EncodeOptions encode,
                 std::chrono::milliseconds period, ChangeHandler on_change,
                 std::function<void()> after_poll)
    : only_(std::move(only)),
      encode_(encode),
      period_(period),
      on_change_(std::move(on_change)),
      after_poll_(std::move(after_poll)) {}

Catalog::~Catalog() { stop(); }

void Catalog::start() {
  poll();
  thread_ = std::thread([this] { run(); });
}

void Catalog::stop() {
  {
    std::lock_guard lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void Catalog::run() {
  std::unique_lock lock(wake_mutex_);
  while (!wake_.wait_for(lock, period_, [this] { return stopping_; })) {
    lock.unlock();
    poll();
    lock.lock();
  }
}

void Catalog::poll() {
  std::lock_guard one_poll(poll_mutex_);
  std::vector<std::string> names = list_streams();
  if (!only_.empty()) {
    std::erase_if(names, [&](const std::string& n) {
      return std::find(only_.begin(), only_.end(), n) == only_.end();
    });
  }
  // Inspect outside the lock: it opens each region, and the page must not wait for that.
  std::vector<std::pair<std::string, Expected<StreamStatus>>> seen;
  seen.reserve(names.size());
  for (const auto& name : names) seen.emplace_back(name, inspect(name));
  const std::int64_t now = monotonic_ns();

  std::vector<AdvertisedStream> added;
  std::vector<std::uint32_t> removed;
  {
    std::lock_guard lock(mutex_);
    for (auto it = streams_.begin(); it != streams_.end();) {
      if (std::find(names.begin(), names.end(), it->first) == names.end()) {
        if (it->second.entry.channel) removed.push_back(it->second.entry.channel->id);
        it = streams_.erase(it);
      } else {
        ++it;
      }
    }
    for (auto& [name, result] : seen) {
      Tracked& t = streams_[name];
      t.entry.name = name;
      if (!result) {
        t.entry.status.reset();
        t.entry.problem = result.error().message;
        t.entry.rate_hz = 0;
        t.entry.age_ns = -1;
        continue;  // keep any channel: a stream being replaced is briefly uninspectable
      }
      const StreamStatus& s = *result;
      t.entry.problem.clear();
      // Rate over a window of at least a second; a restarted writer's counter starts again.
      if (t.window_start_ns == 0 || s.frames_published < t.window_frames) {
        t.window_start_ns = now;
        t.window_frames = s.frames_published;
      } else if (now - t.window_start_ns >= kRateWindowNs) {
        t.entry.rate_hz = static_cast<double>(s.frames_published - t.window_frames) * 1e9 /
                          static_cast<double>(now - t.window_start_ns);
        t.window_start_ns = now;
        t.window_frames = s.frames_published;
      }
      if (!s.writer_alive) t.entry.rate_hz = 0;
      t.entry.age_ns = s.latest_publish_ns == 0 ? -1 : now - s.latest_publish_ns;

      const bool changed = !t.entry.channel || !(t.layout == s.layout) || t.capacity != s.capacity;
      if (changed) {
        if (t.entry.channel) removed.push_back(t.entry.channel->id);
        t.entry.channel.reset();
        t.layout = s.layout;
        t.capacity = s.capacity;
        if (auto schema = schema_for(s.layout, encode_)) {
          Channel c;
          c.id = next_channel_id_++;
          c.topic = name;
          c.encoding = schema->message_encoding;
          c.schema_name = schema->name;
          c.schema_encoding = schema->encoding;
          c.schema = schema->text;
          t.entry.channel = c;
          added.push_back({std::move(c), s.layout});
        }
      }
      t.entry.status = s;
    }
  }
  if ((!added.empty() || !removed.empty()) && on_change_) on_change_(added, removed);
  if (after_poll_) after_poll_();
}

std::vector<StreamEntry> Catalog::snapshot() const {
  std::lock_guard lock(mutex_);
  std::vector<StreamEntry> out;
  out.reserve(streams_.size());
  for (const auto& [name, t] : streams_) out.push_back(t.entry);
  return out;
}

std::optional<StreamEntry> Catalog::find(const std::string& name) const {
  std::lock_guard lock(mutex_);
  const auto it = streams_.find(name);
  if (it == streams_.end()) return std::nullopt;
  return it->second.entry;
}

}  // namespace sim::foxglove
