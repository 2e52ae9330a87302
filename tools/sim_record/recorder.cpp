// SPDX-License-Identifier: Apache-2.0
#include "recorder.hpp"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>

#include "sim/clock.hpp"
#include "sim/mcap/layout_metadata.hpp"
#include "sim/reader.hpp"
#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"
#include "sim/ros2/metadata.hpp"
#include "sim/ros2/type_hash.hpp"

namespace sim::record {

namespace {

// What a message is: a frame (of its ROS 2 type), or what travels beside the frames: the
// calibration beside each image, the mountings on /tf_static, each stream's clock on /diagnostics.
enum class Kind { frame, camera_info, tf_static, clock };

// One serialized message on its way to the writer thread.
struct Pending {
  std::size_t stream = 0;
  Kind kind = Kind::frame;
  ros2::MessageType type = ros2::MessageType::image;
  Layout layout{};
  std::uint64_t capacity = 0;
  mcap::MessageHeader header{};
  std::vector<std::byte> data;
};

// Many stream threads in, one writer thread out, bounded by bytes. Buffers come back to be
// reused so a steady recording allocates nothing per frame.
class MessageQueue {
 public:
  explicit MessageQueue(std::uint64_t limit) : limit_(limit) {}

  std::vector<std::byte> buffer(std::size_t size) {
    std::vector<std::byte> out;
    {
      std::lock_guard lock(mutex_);
      // The spare closest in size above `size`, so large frames reuse large buffers.
      auto best = spare_.end();
      for (auto it = spare_.begin(); it != spare_.end(); ++it) {
        if (it->capacity() >= size && (best == spare_.end() || it->capacity() < best->capacity())) {
          best = it;
        }
      }
      if (best != spare_.end()) {
        out = std::move(*best);
        spare_.erase(best);
      }
    }
    out.resize(size);
    return out;
  }
  void recycle(std::vector<std::byte>&& buffer) {
    std::lock_guard lock(mutex_);
    if (spare_.size() < 16) spare_.push_back(std::move(buffer));
  }

  // Waits for room (a message larger than the limit goes alone); false once `stop` is set.
  bool push(Pending&& item, const std::atomic<bool>& stop) {
    std::unique_lock lock(mutex_);
    while (!items_.empty() && bytes_ + item.data.size() > limit_) {
      if (stop.load()) return false;
      not_full_.wait_for(lock, std::chrono::milliseconds(50));
    }
    bytes_ += item.data.size();
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  // The next message; nullopt once closed and drained.
  std::optional<Pending> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return !items_.empty() || closed_; });
    if (items_.empty()) return std::nullopt;
    Pending item = std::move(items_.front());
    items_.pop_front();
    bytes_ -= item.data.size();
    not_full_.notify_all();
    return item;
  }
  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
  }
  std::uint64_t bytes() const {
    std::lock_guard lock(mutex_);
    return bytes_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<Pending> items_;
  std::vector<std::vector<std::byte>> spare_;
  std::uint64_t bytes_ = 0;
  std::uint64_t limit_;
  bool closed_ = false;
};

struct StreamState {
  std::string name;
  std::string frame_id;  // the sensor's frame, else the stream name without its slash: "lidar_top"
  Reader reader;
  std::uint64_t sensor_generation = UINT64_MAX;  // of the description below; MAX: not looked yet
  std::uint64_t sensor_failed = UINT64_MAX;      // a generation whose description could not be read
  std::vector<std::byte> camera_info;            // CameraInfo to restamp per image; empty: none
  std::string hardware_id;                       // the sensor's serial, else the stream name
  std::uint64_t clock_generation = UINT64_MAX;   // of the clock recorded last; MAX: not looked yet
  std::optional<ClockStatus> clock;              // as recorded last
  std::atomic<std::uint64_t> frames{0};
  std::atomic<std::uint64_t> bytes{0};
  std::atomic<std::uint64_t> skipped{0};  // the reader's count of frames it never saw
  std::atomic<std::uint64_t> lapped{0};   // overwritten while being serialized
  std::atomic<std::uint64_t> unrecordable{0};
  // The stream's newest frame when the recording opened it, and the frames published after that
  // but replaced before the first read (the reader counts gaps only from a frame it has read).
  std::uint64_t seq_at_open = 0;
  bool read_once = false;
  std::atomic<std::uint64_t> replaced_before_first_read{0};

  StreamState(std::string n, Reader r) : name(std::move(n)), reader(std::move(r)) {
    frame_id = default_frame_id();
    hardware_id = name;
    seq_at_open = reader.status().latest_seq;
  }
  std::string default_frame_id() const {
    return name.substr(name.find_first_not_of('/') == std::string::npos ? 0 : 1);
  }
};

// A sensor's mounting as /tf_static carries it, owning its frame names.
struct OwnedMounting {
  std::string parent;
  std::string child;
  Mounting mounting;
  friend bool operator==(const OwnedMounting&, const OwnedMounting&) = default;
};

// The topic of a stream's frames, laid out as sim_dds_bridge publishes them: images at
// <stream>/image_raw (JPEG at <stream>/image_raw/compressed), their calibration at the sibling
// <stream>/camera_info, point clouds at the stream's name.
std::string frame_topic(const std::string& stream, ros2::MessageType type) {
  switch (type) {
    case ros2::MessageType::image: return stream + "/image_raw";
    case ros2::MessageType::compressed_image: return stream + "/image_raw/compressed";
    case ros2::MessageType::point_cloud2: break;
  }
  return stream;
}

// /diagnostics as diagnostic_updater offers it: keep last 10, reliable, volatile.
const std::string& diagnostics_qos_yaml() {
  static const std::string yaml =
      "- history: 1\n"
      "  depth: 10\n"
      "  reliability: 1\n"
      "  durability: 2\n"
      "  deadline:\n    sec: 0\n    nsec: 0\n"
      "  lifespan:\n    sec: 0\n    nsec: 0\n"
      "  liveliness: 1\n"
      "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
      "  avoid_ros_namespace_conventions: false\n";
  return yaml;
}

// /tf_static as tf2's static broadcaster offers it: keep last 1, reliable, transient local, so
// `ros2 bag play` republishes it latched and late subscribers get it.
const std::string& latched_qos_yaml() {
  static const std::string yaml =
      "- history: 1\n"
      "  depth: 1\n"
      "  reliability: 1\n"
      "  durability: 1\n"
      "  deadline:\n    sec: 0\n    nsec: 0\n"
      "  lifespan:\n    sec: 0\n    nsec: 0\n"
      "  liveliness: 1\n"
      "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
      "  avoid_ros_namespace_conventions: false\n";
  return yaml;
}

}  // namespace

struct Recorder::Impl {
  RecorderOptions options;
  std::optional<mcap::Writer> writer;
  std::atomic<std::uint64_t> file_bytes{0};
  std::vector<std::unique_ptr<StreamState>> streams;
  MessageQueue queue;
  std::atomic<bool> stop_streams{false};
  std::atomic<bool> write_failed{false};
  std::vector<std::thread> stream_threads;
  std::thread writer_thread;
  std::int64_t start_monotonic_ns = 0;
  std::int64_t realtime_minus_monotonic_ns = 0;  // turns publish times into epoch times
  // The writer thread's: schemas by type name, channels by (stream, what, capacity).
  std::map<std::string, std::uint16_t> schemas;
  std::map<std::tuple<std::size_t, std::string, std::uint64_t>, std::uint16_t> channels;
  std::map<std::uint16_t, std::size_t> channel_streams;  // frame channel id -> index in `streams`
  std::mutex mountings_mutex;
  std::map<std::size_t, OwnedMounting> mountings;  // by stream index: what /tf_static holds
  bool stopped = false;
  bool closed = false;  // the file is closed: the writer knows what reached it

  mutable std::mutex problem_mutex;
  std::string problem;

  explicit Impl(const RecorderOptions& o) : options(o), queue(o.queue_bytes) {}

  void note(const std::string& sentence) {
    std::lock_guard lock(problem_mutex);
    if (problem.empty()) problem = sentence;
  }

  void run_stream(StreamState& s, std::size_t index) {
    // The clock as it is when recording starts, before any frame (the stream may be idle).
    if (auto sensor = s.reader.sensor_info()) s.hardware_id = ros2::clock_hardware_id(s.name, *sensor);
    if (!clock_changed(s, index, 0, static_cast<std::uint64_t>(realtime_ns()))) return;
    while (!stop_streams.load(std::memory_order_relaxed)) {
      const ReadStatus waited = s.reader.wait(std::chrono::milliseconds(100));
      if (waited == ReadStatus::region_invalid) {
        note("stream " + s.name + " failed validation; restart its writer");
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        continue;
      }
      if (!record_newest(s, index)) return;
    }
    // Stopping: the newest frame published before the stop and not taken yet is recorded too, so
    // a recording ends with the last frame its streams had when the user stopped it.
    record_newest(s, index);
  }

  // Records the stream's newest frame if it is new. False when the recording cannot go on (the
  // clock record or the calibration could not be queued, or the queue refused during a stop).
  bool record_newest(StreamState& s, std::size_t index) {
    Borrow frame = s.reader.borrow();
    s.skipped.store(s.reader.stats().skipped, std::memory_order_relaxed);
    if (frame.status() != ReadStatus::new_frame) return true;
    const FrameInfo& info = frame.info();
    if (!s.read_once) {
      s.read_once = true;
      if (info.seq > s.seq_at_open + 1) {
        s.replaced_before_first_read.store(info.seq - s.seq_at_open - 1, std::memory_order_relaxed);
      }
    }
    if (info.sensor_generation != s.sensor_generation) sensor_changed(s, index, info.sensor_generation);
    if (info.publish_ns < start_monotonic_ns) return true;  // published before recording began

    auto plan = ros2::plan_frame(info, s.frame_id);
    if (!plan) {
      s.unrecordable.fetch_add(1, std::memory_order_relaxed);
      note("a frame of " + s.name + " has no ROS 2 message: " + plan.error().message);
      return true;
    }
    // The one copy: straight from the borrowed slot into the message.
    std::vector<std::byte> data = queue.buffer(plan->size());
    const bool written = plan->write(frame.bytes().first(info.size), data) == plan->size();
    if (!frame.still_valid() || !written) {  // lapped by the writer while we copied
      s.lapped.fetch_add(1, std::memory_order_relaxed);
      queue.recycle(std::move(data));
      return true;
    }
    const auto log_time = static_cast<std::uint64_t>(info.publish_ns + realtime_minus_monotonic_ns);
    // A new clock record goes first, with the frame's log time: a player restores it before
    // the frame it came with.
    if (info.clock_generation != s.clock_generation &&
        !clock_changed(s, index, info.clock_generation, log_time)) {
      return false;
    }
    // The calibration goes first, with the image's stamp and the same log time: a player
    // restores it before the image it belongs to.
    if (!s.camera_info.empty() && !push_camera_info(s, index, info, log_time)) return false;
    Pending item;
    item.stream = index;
    item.type = plan->type();
    item.layout = info.layout;
    item.capacity = s.reader.capacity();
    item.header.sequence = static_cast<std::uint32_t>(info.seq);
    item.header.log_time = log_time;
    item.header.publish_time = static_cast<std::uint64_t>(std::max<std::int64_t>(info.stamp_ns, 0));
    item.data = std::move(data);
    const std::size_t size = item.data.size();
    if (!queue.push(std::move(item), stop_streams)) {
      s.lapped.fetch_add(1, std::memory_order_relaxed);  // taken but not recorded: missed
      return false;
    }
    s.frames.fetch_add(1, std::memory_order_relaxed);
    s.bytes.fetch_add(size, std::memory_order_relaxed);
    return true;
  }

  // A new sensor description (or the first look): the frame id of the messages, the CameraInfo
  // beside images, and the stream's mounting on /tf_static follow it.
  void sensor_changed(StreamState& s, std::size_t index, std::uint64_t generation) {
    auto sensor = s.reader.sensor_info();
    if (!sensor) {
      // Review turn 4 M6: a writer stopped in the middle of an update (SIGSTOP, a debugger, a
      // loaded host) is no final answer: the recording keeps what it has, and the next frame
      // looks again (said once per generation).
      if (s.sensor_failed != generation) note("stream " + s.name + ": " + sensor.error().message);
      s.sensor_failed = generation;
      return;
    }
    s.sensor_generation = generation;
    s.frame_id = s.default_frame_id();
    s.camera_info.clear();
    const std::optional<SensorInfo>& info = *sensor;
    s.hardware_id = ros2::clock_hardware_id(s.name, info);
    if (!info) return set_mounting(index, std::nullopt);
    if (!info->frame_id.empty()) s.frame_id = info->frame_id;
    if (info->calibration && s.reader.layout().kind == LayoutKind::image) {
      auto message = ros2::encode_camera_info({ros2::Time{}, s.frame_id}, *info->calibration);
      if (message) {
        s.camera_info = std::move(*message);
      } else {
        note("the calibration of " + s.name + " cannot be recorded: " + message.error().message);
      }
    }
    if (info->mounting) {
      set_mounting(index, OwnedMounting{info->parent_frame, s.frame_id, *info->mounting});
    } else {
      set_mounting(index, std::nullopt);
    }
  }

  // Records the stream's clock when it differs from the one recorded last (a record the writer
  // rewrote unchanged is not recorded again). False once the recording stops.
  bool clock_changed(StreamState& s, std::size_t index, std::uint64_t generation, std::uint64_t log_time) {
    s.clock_generation = generation;
    auto clock = s.reader.clock();
    if (!clock) {
      note("the clock of " + s.name + " cannot be recorded: " + clock.error().message);
      return true;
    }
    if (!*clock || (s.clock && *s.clock == **clock)) return true;
    s.clock = **clock;
    ros2::DiagnosticArray array;
    array.stamp = ros2::Time::from_ns(static_cast<std::int64_t>(log_time));
    array.status.push_back(ros2::clock_diagnostic(s.name, s.hardware_id, *s.clock, true));
    auto message = ros2::encode_diagnostic_array(array);
    if (!message) {
      note("the clock of " + s.name + " cannot be recorded: " + message.error().message);
      return true;
    }
    Pending item;
    item.stream = index;
    item.kind = Kind::clock;
    item.header.log_time = log_time;
    item.header.publish_time = log_time;
    item.data = std::move(*message);
    return queue.push(std::move(item), stop_streams);
  }

  bool push_camera_info(StreamState& s, std::size_t index, const FrameInfo& info, std::uint64_t log_time) {
    Pending item;
    item.stream = index;
    item.kind = Kind::camera_info;
    item.header.sequence = static_cast<std::uint32_t>(info.seq);
    item.header.log_time = log_time;
    item.header.publish_time = static_cast<std::uint64_t>(std::max<std::int64_t>(info.stamp_ns, 0));
    item.data = queue.buffer(s.camera_info.size());
    std::copy(s.camera_info.begin(), s.camera_info.end(), item.data.begin());
    ros2::restamp(item.data, ros2::Time::from_ns(info.stamp_ns));
    return queue.push(std::move(item), stop_streams);
  }

  // Every mounting in one TFMessage, as tf2's static broadcaster sends it, whenever one changes.
  void set_mounting(std::size_t index, std::optional<OwnedMounting> mounting) {
    std::lock_guard lock(mountings_mutex);
    const auto it = mountings.find(index);
    if (mounting ? it != mountings.end() && it->second == *mounting : it == mountings.end()) return;
    if (mounting) {
      mountings[index] = std::move(*mounting);
    } else {
      mountings.erase(it);
    }
    const std::int64_t now = realtime_ns();
    std::vector<ros2::TransformStamped> transforms;
    for (const auto& [stream, m] : mountings) {
      transforms.push_back({{ros2::Time::from_ns(now), m.parent}, m.child, m.mounting});
    }
    auto message = ros2::encode_tf_message(transforms);
    if (!message) return note("the mountings cannot be recorded: " + message.error().message);
    Pending item;
    item.stream = index;
    item.kind = Kind::tf_static;
    item.header.log_time = static_cast<std::uint64_t>(now);
    item.header.publish_time = static_cast<std::uint64_t>(now);
    item.data = std::move(*message);
    (void)queue.push(std::move(item), stop_streams);
  }

  // The channel of a message: one per stream and layout for frames (a stream whose writer
  // changes its layout gets a second channel on the same topic), one per stream for its
  // calibration, one /tf_static. Every channel carries rosbag2's offered_qos_profiles and
  // topic_type_hash.
  std::uint16_t channel_for(const Pending& item) {
    const std::string& name = streams[item.stream]->name;
    std::string schema_name, schema_text, topic;
    mcap::Metadata metadata;
    std::tuple<std::size_t, std::string, std::uint64_t> key;
    switch (item.kind) {
      case Kind::frame:
        schema_name = ros2::ros_type_name(item.type);
        schema_text = ros2::ros2msg_schema(item.type);
        topic = frame_topic(name, item.type);
        metadata = mcap::stream_metadata(name, item.layout, item.capacity);
        key = {item.stream, item.layout.describe(), item.capacity};
        break;
      case Kind::camera_info:
        schema_name = ros2::camera_info_type_name;
        schema_text = ros2::camera_info_schema();
        topic = ros2::camera_info_topic_for(frame_topic(name, ros2::MessageType::image));
        metadata = {{"offered_qos_profiles", mcap::sensor_data_qos_yaml()}, {"sim.stream", name}};
        key = {item.stream, "camera_info", 0};
        break;
      case Kind::tf_static:
        schema_name = ros2::tf_message_type_name;
        schema_text = ros2::tf_message_schema();
        topic = "/tf_static";
        metadata = {{"offered_qos_profiles", latched_qos_yaml()}};
        key = {SIZE_MAX, "tf_static", 0};
        break;
      case Kind::clock:
        schema_name = ros2::diagnostic_array_type_name;
        schema_text = ros2::diagnostic_array_schema();
        topic = ros2::diagnostics_topic;
        metadata = {{"offered_qos_profiles", diagnostics_qos_yaml()}};
        key = {SIZE_MAX, "diagnostics", 0};
        break;
    }
    if (const auto found = channels.find(key); found != channels.end()) return found->second;
    auto schema = schemas.find(schema_name);
    if (schema == schemas.end()) {
      schema = schemas.emplace(schema_name, writer->add_schema(schema_name, "ros2msg", schema_text)).first;
    }
    metadata["topic_type_hash"] = std::string(ros2::rihs01_type_hash(schema_name));
    const auto id = writer->add_channel(schema->second, topic, "cdr", metadata);
    channels.emplace(key, id);
    if (item.kind == Kind::frame) channel_streams[id] = item.stream;
    return id;
  }

  void run_writer() {
    while (auto item = queue.pop()) {
      if (write_failed.load()) {
        queue.recycle(std::move(item->data));
        continue;  // drain so the stream threads never wait for room again
      }
      item->header.channel_id = channel_for(*item);
      if (auto error = writer->write(item->header, item->data)) {
        note(error->message);
        write_failed.store(true);
      }
      file_bytes.store(writer->bytes_written(), std::memory_order_relaxed);
      queue.recycle(std::move(item->data));
    }
  }

  RecorderProgress snapshot() const {
    RecorderProgress p;
    for (const auto& s : streams) {
      StreamCounters c;
      c.name = s->name;
      c.frames = s->frames.load(std::memory_order_relaxed);  // handed to the writer thread
      c.bytes = s->bytes.load(std::memory_order_relaxed);
      if (closed) {  // the final report counts what is in the file, not what was sent to it
        c.frames = c.bytes = 0;
        for (const auto& [channel, stream] : channel_streams) {
          if (streams[stream].get() != s.get()) continue;
          const auto stored = writer->stored(channel);
          c.frames += stored.messages;
          c.bytes += stored.bytes;
        }
      }
      c.missed = s->skipped.load(std::memory_order_relaxed) + s->lapped.load(std::memory_order_relaxed) +
                 s->replaced_before_first_read.load(std::memory_order_relaxed);
      c.unrecordable = s->unrecordable.load(std::memory_order_relaxed);
      p.streams.push_back(std::move(c));
    }
    p.file_bytes = file_bytes.load(std::memory_order_relaxed);
    p.queued_bytes = queue.bytes();
    return p;
  }

  void shutdown() {
    if (stopped) return;
    stopped = true;
    stop_streams.store(true);
    for (auto& t : stream_threads) t.join();
    queue.close();
    if (writer_thread.joinable()) writer_thread.join();
    if (writer) {
      // The last chunk and the summary are written here: a full disk now fails the recording too.
      if (auto error = writer->close()) {
        note(error->message);
        write_failed.store(true);
      }
      file_bytes.store(writer->bytes_written());
      closed = true;
    }
  }
};

Recorder::Recorder(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Recorder::Recorder(Recorder&&) noexcept = default;
Recorder& Recorder::operator=(Recorder&& other) noexcept {
  if (this != &other) {
    if (impl_) impl_->shutdown();
    impl_ = std::move(other.impl_);
  }
  return *this;
}
Recorder::~Recorder() {
  if (impl_) impl_->shutdown();
}

Expected<Recorder> Recorder::start(const RecorderOptions& options) {
  if (options.streams.empty()) {
    return Error{ErrorCode::invalid_argument, "no stream to record; name streams or pass --all"};
  }
  auto impl = std::make_unique<Impl>(options);
  // The recording begins before any stream is opened: a writer that waits for its first reader
  // (a camera with --wait-for-reader) publishes as soon as one opens, and that frame belongs in
  // the recording.
  impl->start_monotonic_ns = monotonic_ns();
  impl->realtime_minus_monotonic_ns = realtime_ns() - impl->start_monotonic_ns;
  for (const auto& name : options.streams) {
    auto reader = Reader::open(name, {.trust = options.trust});
    if (!reader) return reader.error();
    if (auto type = ros2::message_type_for(reader->layout()); !type) {
      return Error{ErrorCode::invalid_argument,
                   "stream " + name + " cannot be recorded: " + type.error().message};
    }
    impl->streams.push_back(std::make_unique<StreamState>(name, std::move(*reader)));
  }
  auto writer = mcap::Writer::create(options.path, options.writer);
  if (!writer) return writer.error();
  impl->writer.emplace(std::move(*writer));

  Impl* self = impl.get();
  self->writer_thread = std::thread([self] { self->run_writer(); });
  for (std::size_t i = 0; i < self->streams.size(); ++i) {
    self->stream_threads.emplace_back([self, i] { self->run_stream(*self->streams[i], i); });
  }
  return Recorder(std::move(impl));
}

RecorderProgress Recorder::progress() const { return impl_->snapshot(); }

std::string Recorder::problem() const {
  std::lock_guard lock(impl_->problem_mutex);
  return impl_->problem;
}

bool Recorder::failed() const { return impl_->write_failed.load(); }

RecorderProgress Recorder::stop() {
  impl_->shutdown();
  return impl_->snapshot();
}

}  // namespace sim::record
