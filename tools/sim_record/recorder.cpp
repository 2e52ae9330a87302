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
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"

namespace sim::record {

namespace {

// One serialized message on its way to the writer thread.
struct Pending {
  std::size_t stream = 0;
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
  std::string frame_id;  // the stream name without its slash: "lidar_top"
  Reader reader;
  std::atomic<std::uint64_t> frames{0};
  std::atomic<std::uint64_t> bytes{0};
  std::atomic<std::uint64_t> skipped{0};  // the reader's count of frames it never saw
  std::atomic<std::uint64_t> lapped{0};   // overwritten while being serialized
  std::atomic<std::uint64_t> unrecordable{0};

  StreamState(std::string n, Reader r) : name(std::move(n)), reader(std::move(r)) {
    frame_id = name.substr(name.find_first_not_of('/') == std::string::npos ? 0 : 1);
  }
};

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
  std::map<std::uint16_t, std::size_t> channel_streams;  // MCAP channel id -> index in `streams`
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
    while (!stop_streams.load(std::memory_order_relaxed)) {
      const ReadStatus waited = s.reader.wait(std::chrono::milliseconds(100));
      if (waited == ReadStatus::region_invalid) {
        note("stream " + s.name + " failed validation; restart its writer");
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        continue;
      }
      Borrow frame = s.reader.borrow();
      s.skipped.store(s.reader.stats().skipped, std::memory_order_relaxed);
      if (frame.status() != ReadStatus::new_frame) continue;
      const FrameInfo& info = frame.info();
      if (info.publish_ns < start_monotonic_ns) continue;  // published before recording began

      auto plan = ros2::plan_frame(info, s.frame_id);
      if (!plan) {
        s.unrecordable.fetch_add(1, std::memory_order_relaxed);
        note("a frame of " + s.name + " has no ROS 2 message: " + plan.error().message);
        continue;
      }
      // The one copy: straight from the borrowed slot into the message.
      std::vector<std::byte> data = queue.buffer(plan->size());
      const bool written = plan->write(frame.bytes().first(info.size), data) == plan->size();
      if (!frame.still_valid() || !written) {  // lapped by the writer while we copied
        s.lapped.fetch_add(1, std::memory_order_relaxed);
        queue.recycle(std::move(data));
        continue;
      }
      Pending item;
      item.stream = index;
      item.type = plan->type();
      item.layout = info.layout;
      item.capacity = s.reader.capacity();
      item.header.sequence = static_cast<std::uint32_t>(info.seq);
      item.header.log_time = static_cast<std::uint64_t>(info.publish_ns + realtime_minus_monotonic_ns);
      item.header.publish_time = static_cast<std::uint64_t>(std::max<std::int64_t>(info.stamp_ns, 0));
      item.data = std::move(data);
      const std::size_t size = item.data.size();
      if (!queue.push(std::move(item), stop_streams)) break;
      s.frames.fetch_add(1, std::memory_order_relaxed);
      s.bytes.fetch_add(size, std::memory_order_relaxed);
    }
  }

  void run_writer() {
    // One schema per message type; one channel per stream and layout (a stream whose writer
    // changes its layout gets a second channel with the same topic).
    std::map<ros2::MessageType, std::uint16_t> schemas;
    std::map<std::tuple<std::size_t, std::string, std::uint64_t>, std::uint16_t> channels;
    while (auto item = queue.pop()) {
      if (write_failed.load()) {
        queue.recycle(std::move(item->data));
        continue;  // drain so the stream threads never wait for room again
      }
      auto schema = schemas.find(item->type);
      if (schema == schemas.end()) {
        const auto id = writer->add_schema(ros2::ros_type_name(item->type), "ros2msg",
                                           ros2::ros2msg_schema(item->type));
        schema = schemas.emplace(item->type, id).first;
      }
      const auto key = std::make_tuple(item->stream, item->layout.describe(), item->capacity);
      auto channel = channels.find(key);
      if (channel == channels.end()) {
        const std::string& name = streams[item->stream]->name;
        const auto id = writer->add_channel(schema->second, name, "cdr",
                                            mcap::stream_metadata(name, item->layout, item->capacity));
        channel = channels.emplace(key, id).first;
        channel_streams[id] = item->stream;
      }
      item->header.channel_id = channel->second;
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
      c.missed = s->skipped.load(std::memory_order_relaxed) + s->lapped.load(std::memory_order_relaxed);
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

  impl->start_monotonic_ns = monotonic_ns();
  impl->realtime_minus_monotonic_ns = realtime_ns() - impl->start_monotonic_ns;
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
