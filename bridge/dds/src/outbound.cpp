// SPDX-License-Identifier: Apache-2.0
#include "outbound.hpp"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/rtps/common/InstanceHandle.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <vector>

#include "ros_message_type.hpp"
#include "sim/clock.hpp"
#include "sim/imaging/jpeg_encoder.hpp"
#include "sim/reader.hpp"
#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/metadata.hpp"

namespace sim::bridge {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

namespace {

constexpr auto reopen_period = 200ms;  // how often a missing stream is looked for again
constexpr auto wait_slice = 100ms;     // how long one wait for a frame lasts, so stop is prompt
constexpr auto idle_poll = 200ms;      // how often a stream nobody listens to is looked at
constexpr std::int64_t clock_period_ns = 1'000'000'000;  // how often the clock record is read

std::string image_topic(const std::string& base) { return base + "/image_raw"; }
std::string jpeg_topic(const std::string& base) { return base + "/image_raw/compressed"; }

// The topic a frame message of `type` goes to.
std::string topic_for(const std::string& base, ros2::MessageType type) {
  switch (type) {
    case ros2::MessageType::point_cloud2: return base;
    case ros2::MessageType::image: return image_topic(base);
    case ros2::MessageType::compressed_image: return jpeg_topic(base);
  }
  return base;
}

// The remote readers a writer is matched with, as Fast DDS reports them (on its own threads).
class MatchTracker final : public dds::DataWriterListener {
 public:
  void on_publication_matched(dds::DataWriter*, const dds::PublicationMatchedStatus& status) override {
    std::lock_guard lock(mutex_);
    const auto guid = eprosima::fastrtps::rtps::iHandle2GUID(status.last_subscription_handle);
    if (status.current_count_change > 0) readers_.insert(guid);
    if (status.current_count_change < 0) readers_.erase(guid);
    generation_.fetch_add(1);
  }
  std::uint64_t generation() const noexcept { return generation_.load(); }
  std::set<eprosima::fastrtps::rtps::GUID_t> readers() const {
    std::lock_guard lock(mutex_);
    return readers_;
  }
  void clear() {
    std::lock_guard lock(mutex_);
    readers_.clear();
    generation_.fetch_add(1);
  }

 private:
  mutable std::mutex mutex_;
  std::set<eprosima::fastrtps::rtps::GUID_t> readers_;
  std::atomic<std::uint64_t> generation_{0};
};

// One DDS writer of one topic, recreated when the topic or its type changes.
class TopicWriter {
 public:
  TopicWriter(DdsSession& session, QosChoice qos, Counters& counters)
      : session_(session), qos_(qos), counters_(counters) {}
  ~TopicWriter() { session_.delete_writer(writer_); }
  TopicWriter(const TopicWriter&) = delete;
  TopicWriter& operator=(const TopicWriter&) = delete;

  // False (with the reason given to the counters) when no writer could be made.
  bool ensure(const std::string& ros_topic, std::string_view dds_type) {
    if (writer_ != nullptr && ros_topic == ros_topic_ && dds_type == dds_type_) return true;
    session_.delete_writer(std::exchange(writer_, nullptr));
    std::string error;
    ros_topic_ = ros_topic;
    dds_type_ = dds_type;
    tracker_.clear();
    writer_ = session_.create_writer(ros2::dds_topic_name(ros_topic), dds_type, qos_, error, &tracker_);
    if (writer_ == nullptr) counters_.problem(error);
    counters_.connected.store(writer_ != nullptr);
    return writer_ != nullptr;
  }
  bool exists() const { return writer_ != nullptr; }

  // Remote readers matched now (one cheap call; Fast DDS keeps the count), less those that
  // ROS 2's graph says are gone (review M1; recounted only when the matches or the graph changed).
  int matched() {
    if (writer_ == nullptr) return 0;
    dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    int live = status.current_count;
    const std::uint64_t graph = session_.graph_generation();
    if (graph != 0 && live > 0) {
      const std::uint64_t matches = tracker_.generation();
      if (graph != counted_graph_ || matches != counted_matches_ || live != counted_matched_) {
        counted_graph_ = graph;
        counted_matches_ = matches;
        counted_matched_ = live;
        gone_ = 0;
        for (const auto& reader : tracker_.readers()) gone_ += session_.graph_says_gone(reader) ? 1 : 0;
      }
      live = std::max(0, live - gone_);
    }
    counters_.matched.store(live, std::memory_order_relaxed);
    return live;
  }

  // Review M4: a remote reader that discovery announced but that did not match is told why, in
  // one sentence (told once per sentence by the counters).
  void tell_mismatches() {
    if (writer_ == nullptr) return;
    for (const RemoteEndpoint& r : session_.remote_readers(ros2::dds_topic_name(ros_topic_))) {
      if (r.type_name != dds_type_) {
        counters_.problem(ros_topic_ + ": a reader expects the type " + r.type_name +
                          ", but the bridge publishes " + std::string(dds_type_) + " there");
      } else if (r.reliable && !qos_.reliable) {
        counters_.problem(ros_topic_ + ": a reader asks for RELIABLE delivery and does not match "
                          "the bridge's best effort (ROS 2 sensor data); start the bridge with "
                          "--reliable or subscribe with SensorDataQoS");
      } else if (!r.xcdr1) {
        counters_.problem(ros_topic_ + ": a reader accepts only XCDR2 data and does not match; "
                          "ROS 2 nodes and the bridge use XCDR1");
      }
    }
  }

  // Serializes (a frame's one copy) and sends.
  template <typename Message>
  void write(Message& message) {
    counters_.count(counters_.serialized);
    const bool sent = static_cast<bool>(writer_->write(&message));
    if constexpr (std::is_same_v<Message, OutgoingMessage>) {
      if (message.torn) return counters_.count(counters_.torn);
    }
    counters_.count(sent ? counters_.bridged : counters_.failed);
  }

 private:
  DdsSession& session_;
  QosChoice qos_;
  Counters& counters_;
  MatchTracker tracker_;
  dds::DataWriter* writer_ = nullptr;
  std::string ros_topic_;
  std::string_view dds_type_;
  std::uint64_t counted_graph_ = 0;
  std::uint64_t counted_matches_ = 0;
  int counted_matched_ = 0;
  int gone_ = 0;
};

// --max-rate: a frame goes out when at least one period passed since the last one sent, less a
// tenth of it, so a 20 Hz stream limited to 10 Hz sends every other frame despite jitter. The
// options keep the rate from 0.001 Hz up, so the period fits (review L2).
class RateLimit {
 public:
  explicit RateLimit(double hz) : period_ns_(hz > 0 ? static_cast<std::int64_t>(1e9 / hz) : 0) {}
  bool due(std::int64_t now_ns) const {
    return period_ns_ == 0 || last_ns_ == 0 || now_ns - last_ns_ >= period_ns_ - period_ns_ / 10;
  }
  void sent(std::int64_t now_ns) { last_ns_ = now_ns; }

 private:
  std::int64_t period_ns_;
  std::int64_t last_ns_ = 0;
};

}  // namespace

std::vector<std::string> published_topics(const OutboundOptions& options) {
  const std::string& base = options.topic.empty() ? options.stream : options.topic;
  return {base, image_topic(base), jpeg_topic(base), ros2::camera_info_topic_for(image_topic(base))};
}

// The state of one publication while it runs: the writers, the encoder, the stream's sensor.
class Publication {
 public:
  Publication(DdsSession& session, StaticTransforms& transforms, ClockDiagnostics& clocks,
              const OutboundOptions& options, Counters& raw, Counters& compressed,
              Counters& camera_info)
      : transforms_(transforms), clocks_(clocks), options_(options), raw_counters_(raw),
        compressed_counters_(compressed), raw_(session, options.qos, raw),
        compressed_(session, options.qos, compressed), camera_info_(session, options.qos, camera_info),
        rate_(options.max_rate_hz), frame_id_(default_frame_id()) {
    if (options.jpeg_quality) {
      auto created = imaging::JpegEncoder::create(*options.jpeg_quality);
      if (created) {
        encoder_.emplace(std::move(created.value()));
      } else {
        compressed.problem(options.stream + ": " + created.error().message);
      }
    }
  }

  // The stream was (re)opened: its writers for its layout, its sensor description.
  bool opened(Reader& reader, std::string& raw_topic);
  // Nobody listens: look at the stream without waking per frame. False: reopen it.
  bool idle(Reader& reader);
  // Someone listens: wait for the next frame and send it. False: reopen the stream.
  bool serve(Reader& reader);
  // CameraInfo counts on its own (review turn 4 L9): `ros2 topic echo <ns>/camera_info`, or a
  // node that needs only the intrinsics, gets it without anyone reading the images.
  bool wanted() {
    return raw_.matched() > 0 || (can_compress_ && compressed_.matched() > 0) || camera_info_wanted();
  }

 private:
  std::string default_frame_id() const {
    return options_.frame_id.empty() ? options_.stream.substr(1) : options_.frame_id;
  }
  void sensor_changed(const Reader& reader, std::uint64_t generation);
  // Once a second: the stream's clock record and whether its writer lives, for /diagnostics.
  void watch_clock(Reader& reader, bool now = false);
  void count_frames(const FrameInfo& info, bool sent);
  void send_raw(const Borrow& borrow);
  void send_jpeg(const Borrow& borrow);
  void send_camera_info(std::int64_t stamp_ns);
  bool camera_info_wanted() {
    return is_image_ && !camera_info_message_.empty() && camera_info_.exists() && camera_info_.matched() > 0;
  }

  StaticTransforms& transforms_;
  ClockDiagnostics& clocks_;
  const OutboundOptions& options_;
  Counters& raw_counters_;
  Counters& compressed_counters_;
  TopicWriter raw_;
  TopicWriter compressed_;
  TopicWriter camera_info_;
  std::optional<imaging::JpegEncoder> encoder_;
  RateLimit rate_;
  bool can_compress_ = false;
  bool compress_refused_ = false;
  bool is_image_ = false;
  std::uint64_t last_seq_ = 0;
  std::optional<std::uint64_t> generation_;
  std::string frame_id_;
  std::string hardware_id_;                     // the sensor's serial, else the stream name
  std::vector<std::byte> camera_info_message_;  // empty: no calibration
  std::int64_t clock_read_ns_ = 0;              // monotonic time the clock was last read
};

bool Publication::opened(Reader& reader, std::string& raw_topic) {
  auto type = ros2::message_type_for(reader.layout());
  if (!type) {
    raw_counters_.problem(options_.stream + ": " + type.error().message);
    return false;
  }
  // Creating the writers as soon as the stream's kind is known makes the topics visible (and
  // matchable) before the first frame is worth sending.
  raw_topic = topic_for(options_.topic, *type);
  if (!raw_.ensure(raw_topic, ros2::dds_type_name(*type))) return false;
  is_image_ = *type != ros2::MessageType::point_cloud2;
  can_compress_ = encoder_ && *type == ros2::MessageType::image &&
                  imaging::JpegEncoder::encodes(reader.layout().image.format);
  if (options_.jpeg_quality && !can_compress_ && !compress_refused_) {
    compressed_counters_.problem(options_.stream + ": --compress jpeg needs a mono8, bgr8, rgb8, "
                                 "bgra8 or rgba8 image stream; no CompressedImage is published");
    compress_refused_ = true;
  }
  if (can_compress_ &&
      !compressed_.ensure(jpeg_topic(options_.topic), ros2::dds_type_name(ros2::MessageType::compressed_image))) {
    return false;
  }
  generation_.reset();
  sensor_changed(reader, 0);
  watch_clock(reader, true);
  return true;
}

void Publication::watch_clock(Reader& reader, bool now) {
  const std::int64_t t = monotonic_ns();
  if (!now && t - clock_read_ns_ < clock_period_ns) return;
  clock_read_ns_ = t;
  auto clock = reader.clock();
  if (!clock) {
    raw_counters_.problem(options_.stream + ": " + clock.error().message);
    return;
  }
  clocks_.set(options_.stream, hardware_id_, *clock, reader.writer_alive());
}

// A new sensor description (or the first look at one): the frame id, the CameraInfo message and
// the mounting on /tf_static follow it.
void Publication::sensor_changed(const Reader& reader, std::uint64_t generation) {
  if (generation_ == generation) return;
  generation_ = generation;
  auto sensor = reader.sensor_info();
  if (!sensor) {
    raw_counters_.problem(options_.stream + ": " + sensor.error().message);
    return;
  }
  const std::optional<SensorInfo>& info = *sensor;
  hardware_id_ = ros2::clock_hardware_id(options_.stream, info);
  frame_id_ = options_.frame_id.empty() && info && !info->frame_id.empty() ? info->frame_id
                                                                            : default_frame_id();
  camera_info_message_.clear();
  if (is_image_ && info && info->calibration) {
    auto message = ros2::encode_camera_info({ros2::Time{}, frame_id_}, *info->calibration);
    if (!message) {
      raw_counters_.problem(options_.stream + ": " + message.error().message);
    } else {
      camera_info_message_ = std::move(message.value());
      camera_info_.ensure(ros2::camera_info_topic_for(image_topic(options_.topic)),
                          ros2::camera_info_dds_type_name);
    }
  }
  // The mounting goes under the frame the messages carry, --frame-id's when given (review turn 4
  // L2: else the images' frame was not in the tree).
  std::optional<SensorInfo> mounted = info;
  if (mounted) mounted->frame_id = frame_id_;
  transforms_.set(options_.stream, mounted);
}

void Publication::count_frames(const FrameInfo& info, bool sent) {
  const std::uint64_t frames = last_seq_ == 0 || info.seq <= last_seq_ ? 1 : info.seq - last_seq_;
  last_seq_ = info.seq;
  raw_counters_.frames_seen.fetch_add(frames, std::memory_order_relaxed);
  if (!sent) raw_counters_.no_reader.fetch_add(frames, std::memory_order_relaxed);
}

bool Publication::idle(Reader& reader) {
  raw_.tell_mismatches();
  if (can_compress_) compressed_.tell_mismatches();
  std::this_thread::sleep_for(idle_poll);
  watch_clock(reader);
  const Borrow borrow = reader.borrow();  // no copy: only the frame's number and description
  if (borrow.status() == ReadStatus::region_invalid) return false;
  if (borrow.status() == ReadStatus::new_frame) {
    count_frames(borrow.info(), false);
    sensor_changed(reader, borrow.info().sensor_generation);
  }
  return true;
}

bool Publication::serve(Reader& reader) {
  const ReadStatus waited = reader.wait(wait_slice);
  if (waited == ReadStatus::region_invalid) return false;
  watch_clock(reader);
  if (waited != ReadStatus::new_frame) return true;
  const Borrow borrow = reader.borrow();
  if (borrow.status() != ReadStatus::new_frame) return true;
  const FrameInfo& info = borrow.info();
  sensor_changed(reader, info.sensor_generation);
  const bool raw_wanted = raw_.matched() > 0;
  const bool jpeg_wanted = can_compress_ && compressed_.matched() > 0;
  count_frames(info, raw_wanted || jpeg_wanted);
  if (!raw_wanted && !jpeg_wanted && !camera_info_wanted()) return true;
  const std::int64_t now = monotonic_ns();
  if (!rate_.due(now)) {
    raw_counters_.count(raw_counters_.skipped_rate);
    return true;
  }
  rate_.sent(now);
  if (raw_wanted) send_raw(borrow);
  if (jpeg_wanted) send_jpeg(borrow);
  if (is_image_) send_camera_info(info.stamp_ns);
  return true;
}

void Publication::send_raw(const Borrow& borrow) {
  const FrameInfo& info = borrow.info();
  // The frame's own kind decides the message (a replaced region may have a new layout).
  auto type = ros2::message_type_for(info.layout);
  if (!type || !raw_.ensure(topic_for(options_.topic, *type), ros2::dds_type_name(*type))) return;
  auto plan = ros2::plan_frame(info, frame_id_);
  if (!plan) {
    raw_counters_.count(raw_counters_.failed);
    raw_counters_.problem(options_.stream + ": " + plan.error().message);
    return;
  }
  OutgoingMessage message{&plan.value(), borrow.bytes().first(info.size), &borrow};
  raw_.write(message);
}

void Publication::send_jpeg(const Borrow& borrow) {
  const FrameInfo& info = borrow.info();
  if (info.layout.kind != LayoutKind::image || !imaging::JpegEncoder::encodes(info.layout.image.format)) {
    return;
  }
  compressed_counters_.count(compressed_counters_.frames_seen);
  // Into the encoder's own buffer, from which serializing is the JPEG's one copy.
  auto jpeg = encoder_->encode(info.layout.image, borrow.bytes().first(info.size));
  if (!borrow.still_valid()) {  // the encoder read a slot being overwritten: drop its output
    compressed_counters_.count(compressed_counters_.torn);
  } else if (!jpeg) {
    compressed_counters_.count(compressed_counters_.failed);
    compressed_counters_.problem(options_.stream + ": " + jpeg.error().message);
  } else {
    const ros2::Header header{ros2::Time::from_ns(info.stamp_ns), frame_id_};
    auto plan = ros2::plan_compressed_image("jpeg", jpeg->size(), header);
    if (plan) {
      OutgoingMessage message{&plan.value(), *jpeg, nullptr};
      compressed_.write(message);
    }
  }
}

// The calibration beside the image: the identical stamp and frame_id, so image_transport's
// exact-time synchroniser and Foxglove pair them.
void Publication::send_camera_info(std::int64_t stamp_ns) {
  if (camera_info_message_.empty() || !camera_info_.exists() || camera_info_.matched() == 0) return;
  ros2::restamp(camera_info_message_, ros2::Time::from_ns(stamp_ns));
  SerializedMessage message{camera_info_message_};
  camera_info_.write(message);
}

std::string announced_topic(const OutboundOptions& options) {
  const std::string base = options.topic.empty() ? options.stream : options.topic;
  if (auto status = inspect(options.stream)) {
    if (auto type = ros2::message_type_for(status->layout)) return topic_for(base, *type);
  }
  return base + "[/image_raw]";
}

Outbound::Outbound(DdsSession& session, StaticTransforms& transforms, ClockDiagnostics& clocks,
                   OutboundOptions options)
    : session_(session), transforms_(transforms), clocks_(clocks), options_(std::move(options)) {
  if (options_.topic.empty()) options_.topic = options_.stream;
  raw_topic_ = options_.topic;
  thread_ = std::thread([this] { run(); });
}

Outbound::~Outbound() { stop(); }

void Outbound::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

std::string Outbound::raw_topic() const {
  std::lock_guard lock(topic_mutex_);
  return raw_topic_;
}
std::string Outbound::compressed_topic() const { return jpeg_topic(options_.topic); }
std::string Outbound::camera_info_topic() const {
  return ros2::camera_info_topic_for(image_topic(options_.topic));
}

void Outbound::set_raw_topic(std::string topic) {
  std::lock_guard lock(topic_mutex_);
  raw_topic_ = std::move(topic);
}

void Outbound::run() {
  Publication publication(session_, transforms_, clocks_, options_, raw_, compressed_, camera_info_);
  std::optional<Reader> reader;
  while (!stop_.load(std::memory_order_relaxed)) {
    if (!reader) {
      auto opened = Reader::open(options_.stream, {.trust = options_.trust});
      if (!opened) {
        raw_.connected.store(false);
        clocks_.writer_gone(options_.stream);
        if (opened.error().code != ErrorCode::not_found) raw_.problem(opened.error().message);
        std::this_thread::sleep_for(reopen_period);
        continue;
      }
      std::string topic;
      if (!publication.opened(*opened, topic)) {  // told once through the counters
        std::this_thread::sleep_for(reopen_period);
        continue;
      }
      set_raw_topic(std::move(topic));
      reader.emplace(std::move(opened.value()));
    }
    const bool ok = publication.wanted() ? publication.serve(*reader) : publication.idle(*reader);
    if (!ok) {
      raw_.problem("the stream " + options_.stream + " became invalid; opening it again");
      clocks_.writer_gone(options_.stream);
      reader.reset();
    }
  }
}

}  // namespace sim::bridge
