// SPDX-License-Identifier: Apache-2.0
#include "catalog.hpp"

#include <algorithm>
#include <cstdio>

#include "sim/clock.hpp"
#include "sim/ros2/diagnostics.hpp"

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

  CatalogChanges changes;
  {
    std::lock_guard lock(mutex_);
    for (auto it = streams_.begin(); it != streams_.end();) {
      if (std::find(names.begin(), names.end(), it->first) == names.end()) {
        for (const auto& c : {it->second.entry.channel, it->second.entry.calibration_channel}) {
          if (c) changes.removed.push_back(c->id);
        }
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
      track(t, s, changes);
      t.entry.status = s;
    }
    track_transforms(changes);
    track_clocks(changes);
  }
  if (!changes.empty() && on_change_) on_change_(changes);
  if (after_poll_) after_poll_();
}

Channel Catalog::new_channel(std::string topic, const MessageSchema& schema) {
  Channel c;
  c.id = next_channel_id_++;
  c.topic = std::move(topic);
  c.encoding = schema.message_encoding;
  c.schema_name = schema.name;
  c.schema_encoding = schema.encoding;
  c.schema = schema.text;
  return c;
}

// The stream's frame channel (a new id when its layout changes, as Foxglove ids must keep their
// schema) and its calibration channel.
void Catalog::track(Tracked& t, const StreamStatus& s, CatalogChanges& changes) {
  const bool changed = !t.entry.channel || !(t.layout == s.layout) || t.capacity != s.capacity;
  if (changed) {
    if (t.entry.channel) changes.removed.push_back(t.entry.channel->id);
    if (t.entry.calibration_channel) changes.removed.push_back(t.entry.calibration_channel->id);
    t.entry.channel.reset();
    t.entry.calibration_channel.reset();
    t.sensor.reset();
    t.layout = s.layout;
    t.capacity = s.capacity;
    if (auto schema = schema_for(s.layout, encode_)) {
      std::string topic = t.entry.name;
      if (s.layout.kind == LayoutKind::image) {
        topic = image_topic(t.entry.name, schema->name != "sensor_msgs/msg/Image");
      }
      t.entry.channel = new_channel(std::move(topic), *schema);
      changes.added.push_back({*t.entry.channel, t.entry.name, s.layout, nullptr});
    }
  }
  if (!t.entry.channel) return;
  if (s.sensor == t.sensor) return;  // after a layout change t.sensor is empty
  track_calibration(t, s.sensor, changes);
  t.sensor = s.sensor;
}

void Catalog::track_calibration(Tracked& t, const std::optional<SensorInfo>& sensor,
                                CatalogChanges& changes) {
  const bool calibrated =
      sensor && sensor->calibration && t.layout.kind == LayoutKind::image;
  if (!calibrated) {
    if (t.entry.calibration_channel) changes.removed.push_back(t.entry.calibration_channel->id);
    t.entry.calibration_channel.reset();
    return;
  }
  const bool existed = t.entry.calibration_channel.has_value();
  if (existed && t.sensor && t.sensor->calibration == sensor->calibration &&
      frame_of(t.entry.name, t.sensor) == frame_of(t.entry.name, sensor)) {
    return;  // only the mounting or the identity changed
  }
  if (!existed) {
    t.entry.calibration_channel =
        new_channel(calibration_topic(t.entry.name),
                    {"cdr", std::string(kCalibrationSchemaName), "ros2msg",
                     std::string(calibration_schema())});
  }
  auto message = std::make_shared<Message>();
  message->channel_id = t.entry.calibration_channel->id;
  message->timestamp_ns = static_cast<std::uint64_t>(realtime_ns());
  message->payload = encode_calibration(*sensor->calibration, frame_of(t.entry.name, sensor),
                                        static_cast<std::int64_t>(message->timestamp_ns));
  if (existed) {
    changes.updated.push_back(std::move(message));
  } else {
    changes.added.push_back(
        {*t.entry.calibration_channel, t.entry.name, t.layout, std::move(message)});
  }
}

// Every mounting the streams know, one per frame. Two streams that mount one frame differently
// (a camera's raw and JPEG streams, one remounted) cannot both be right (review L10): the stream
// whose name sorts last wins, as it does in tf2 from sim_dds_bridge's /tf_static (which lists
// every stream in name order, and tf2 keeps the last transform of a frame); both streams carry
// the sentence (the page shows it) and it is said once on stderr.
std::vector<FrameTransform> Catalog::collect_mountings() {
  std::vector<FrameTransform> transforms;
  std::map<std::string, std::string> mounted_by;  // frame -> the stream whose mounting is kept
  for (auto& [name, t] : streams_) t.entry.mounting_problem.clear();
  for (auto& [name, t] : streams_) {
    if (!t.sensor || !t.sensor->mounting) continue;
    FrameTransform f{t.sensor->parent_frame, frame_of(name, t.sensor), *t.sensor->mounting};
    const auto same = std::find_if(transforms.begin(), transforms.end(),
                                   [&](const FrameTransform& o) { return o.child == f.child; });
    if (same == transforms.end()) {
      mounted_by[f.child] = name;
      transforms.push_back(std::move(f));
      continue;
    }
    if (*same == f) continue;  // the same mounting twice: nothing to choose
    std::string& earlier = mounted_by[f.child];
    const std::string sentence =
        "streams " + earlier + " and " + name + " both mount frame " + f.child + ", differently; " +
        name + "'s mounting is used (the later name, as tf2 keeps from sim_dds_bridge's /tf_static): give "
        "them the same mounting or frames of their own";
    streams_.at(earlier).entry.mounting_problem = sentence;
    t.entry.mounting_problem = sentence;
    if (told_conflicts_.insert(sentence).second) std::fprintf(stderr, "sim_foxglove: %s\n", sentence.c_str());
    earlier = name;
    *same = std::move(f);
  }
  return transforms;
}

// One latched message with every mounting the streams know, changed when any of them changes.
void Catalog::track_transforms(CatalogChanges& changes) {
  std::vector<FrameTransform> transforms = collect_mountings();
  if (transforms == transforms_) return;
  transforms_ = transforms;
  if (transforms.empty()) {
    changes.removed.push_back(transforms_channel_->id);
    transforms_channel_.reset();
    return;
  }
  const bool added = !transforms_channel_;
  if (added) {
    transforms_channel_ = new_channel(std::string(kTransformsTopic),
                                      {"cdr", std::string(kTransformsSchemaName), "ros2msg",
                                       std::string(transforms_schema())});
  }
  auto message = std::make_shared<Message>();
  message->channel_id = transforms_channel_->id;
  message->timestamp_ns = static_cast<std::uint64_t>(realtime_ns());
  message->payload =
      encode_transforms(transforms, static_cast<std::int64_t>(message->timestamp_ns));
  if (added) {
    changes.added.push_back({*transforms_channel_, "", Layout{}, std::move(message)});
  } else {
    changes.updated.push_back(std::move(message));
  }
}

// One latched DiagnosticArray with every inspected stream's clock, sent anew when any changes (a
// driver's clock watch rewrites the record about once a second).
void Catalog::track_clocks(CatalogChanges& changes) {
  std::map<std::string, ClockEntry> clocks;
  for (const auto& [name, t] : streams_) {
    if (!t.entry.status) continue;
    const StreamStatus& s = *t.entry.status;
    clocks[name] = ClockEntry{ros2::clock_hardware_id(name, s.sensor), s.clock, s.writer_alive};
  }
  if (clocks == clocks_) return;
  clocks_ = clocks;
  if (clocks.empty()) {
    if (diagnostics_channel_) changes.removed.push_back(diagnostics_channel_->id);
    diagnostics_channel_.reset();
    return;
  }
  const std::int64_t now = realtime_ns();
  ros2::DiagnosticArray array;
  array.stamp = ros2::Time::from_ns(now);
  for (const auto& [name, c] : clocks) {
    array.status.push_back(ros2::clock_diagnostic(name, c.hardware_id, c.clock, c.writer_alive));
  }
  auto bytes = ros2::encode_diagnostic_array(array);
  if (!bytes) return;  // a record too long for a status: the last message stays
  const bool added = !diagnostics_channel_;
  if (added) {
    diagnostics_channel_ = new_channel(std::string(ros2::diagnostics_topic),
                                       {"cdr", std::string(ros2::diagnostic_array_type_name),
                                        "ros2msg", std::string(ros2::diagnostic_array_schema())});
  }
  auto message = std::make_shared<Message>();
  message->channel_id = diagnostics_channel_->id;
  message->timestamp_ns = static_cast<std::uint64_t>(now);
  message->payload = std::move(*bytes);
  if (added) {
    changes.added.push_back({*diagnostics_channel_, "", Layout{}, std::move(message)});
  } else {
    changes.updated.push_back(std::move(message));
  }
}

std::vector<StreamEntry> Catalog::snapshot() const {
  std::lock_guard lock(mutex_);
  std::vector<StreamEntry> out;
  out.reserve(streams_.size());
  for (const auto& [name, t] : streams_) out.push_back(t.entry);
  return out;
}

std::vector<FrameTransform> Catalog::mountings() const {
  std::lock_guard lock(mutex_);
  return transforms_;
}

std::optional<StreamEntry> Catalog::find(const std::string& name) const {
  std::lock_guard lock(mutex_);
  const auto it = streams_.find(name);
  if (it == streams_.end()) return std::nullopt;
  return it->second.entry;
}

}  // namespace sim::foxglove
