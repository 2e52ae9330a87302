// SPDX-License-Identifier: Apache-2.0
#include "outbound.hpp"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>

#include <chrono>

#include "ros_message_type.hpp"
#include "sim/clock.hpp"
#include "sim/imaging/jpeg_encoder.hpp"
#include "sim/reader.hpp"

namespace sim::bridge {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

namespace {

constexpr auto reopen_period = 200ms;  // how often a missing stream is looked for again
constexpr auto wait_slice = 100ms;     // how long one wait for a frame lasts, so stop is prompt

// One DDS writer of one topic, recreated when the stream's message type changes.
class TopicWriter {
 public:
  TopicWriter(DdsSession& session, std::string dds_topic, QosChoice qos, Counters& counters)
      : session_(session), dds_topic_(std::move(dds_topic)), qos_(qos), counters_(counters) {}
  ~TopicWriter() { session_.delete_writer(writer_); }
  TopicWriter(const TopicWriter&) = delete;
  TopicWriter& operator=(const TopicWriter&) = delete;

  // False (with the reason given to the counters) when no writer could be made.
  bool ensure(ros2::MessageType type) {
    if (writer_ != nullptr && type_ == type) return true;
    session_.delete_writer(std::exchange(writer_, nullptr));
    std::string error;
    writer_ = session_.create_writer(dds_topic_, type, qos_, error);
    type_ = type;
    if (writer_ == nullptr) counters_.problem(error);
    return writer_ != nullptr;
  }

  // Remote readers matched now (one cheap call; Fast DDS keeps the count).
  int matched() {
    if (writer_ == nullptr) return 0;
    dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    counters_.matched.store(status.current_count, std::memory_order_relaxed);
    return status.current_count;
  }

  // Serializes (the one copy) and sends.
  void write(OutgoingMessage& message) {
    counters_.count(counters_.serialized);
    const auto rc = writer_->write(&message);
    if (message.torn) {
      counters_.count(counters_.torn);
    } else if (rc) {
      counters_.count(counters_.bridged);
    } else {
      counters_.count(counters_.failed);
    }
  }

 private:
  DdsSession& session_;
  std::string dds_topic_;
  QosChoice qos_;
  Counters& counters_;
  dds::DataWriter* writer_ = nullptr;
  ros2::MessageType type_ = ros2::MessageType::image;
};

// --max-rate: a frame goes out when at least one period passed since the last one sent, less a
// tenth of it, so a 20 Hz stream limited to 10 Hz sends every other frame despite jitter.
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

Outbound::Outbound(DdsSession& session, OutboundOptions options)
    : session_(session), options_(std::move(options)) {
  if (options_.topic.empty()) options_.topic = options_.stream;
  if (options_.frame_id.empty()) options_.frame_id = options_.stream.substr(1);
  thread_ = std::thread([this] { run(); });
}

Outbound::~Outbound() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void Outbound::run() {
  TopicWriter raw(session_, ros2::dds_topic_name(options_.topic), options_.qos, raw_);
  std::optional<TopicWriter> compressed;
  std::optional<imaging::JpegEncoder> encoder;
  if (options_.jpeg_quality) {
    auto created = imaging::JpegEncoder::create(*options_.jpeg_quality);
    if (created) {
      compressed.emplace(session_, ros2::dds_topic_name(options_.topic + "/compressed"),
                         options_.qos, compressed_);
      encoder.emplace(std::move(created.value()));
    } else {
      compressed_.problem(options_.stream + ": " + created.error().message);
    }
  }
  RateLimit rate(options_.max_rate_hz);
  std::optional<Reader> reader;
  bool compress_refused = false;

  while (!stop_.load(std::memory_order_relaxed)) {
    if (!reader) {
      auto opened = Reader::open(options_.stream, {.trust = options_.trust});
      if (!opened) {
        raw_.connected.store(false);
        if (opened.error().code != ErrorCode::not_found) raw_.problem(opened.error().message);
        std::this_thread::sleep_for(reopen_period);
        continue;
      }
      reader.emplace(std::move(opened.value()));
      raw_.connected.store(true);
    }
    const ReadStatus waited = reader->wait(wait_slice);
    if (waited == ReadStatus::region_invalid) {
      raw_.problem("the stream " + options_.stream + " became invalid; opening it again");
      reader.reset();
      continue;
    }
    // Creating the writers as soon as the stream's kind is known makes the topic visible (and
    // matchable) before the first frame is worth sending.
    auto type = ros2::message_type_for(reader->layout());
    if (!type) {
      raw_.problem(options_.stream + ": " + type.error().message);
      reader.reset();
      std::this_thread::sleep_for(reopen_period);
      continue;
    }
    if (!raw.ensure(*type)) {  // told once through the counters; try again later
      std::this_thread::sleep_for(reopen_period);
      continue;
    }
    const bool can_compress = compressed && *type == ros2::MessageType::image &&
                              imaging::JpegEncoder::encodes(reader->layout().image.format);
    if (compressed && !can_compress && !compress_refused) {
      compressed_.problem(options_.stream + ": --compress jpeg needs a mono8, bgr8, rgb8, bgra8 "
                          "or rgba8 image stream; no CompressedImage is published");
      compress_refused = true;
    }
    if (can_compress && !compressed->ensure(ros2::MessageType::compressed_image)) {
      std::this_thread::sleep_for(reopen_period);
      continue;
    }
    if (waited != ReadStatus::new_frame) {
      raw.matched();
      if (can_compress) compressed->matched();
      continue;
    }

    const Borrow borrow = reader->borrow();
    if (borrow.status() != ReadStatus::new_frame) continue;
    raw_.count(raw_.frames_seen);
    const bool raw_wanted = raw.matched() > 0;
    const bool jpeg_wanted = can_compress && compressed->matched() > 0;
    if (!raw_wanted && !jpeg_wanted) {
      raw_.count(raw_.no_reader);  // nothing serialized, nothing copied
      continue;
    }
    const std::int64_t now = monotonic_ns();
    if (!rate.due(now)) {
      raw_.count(raw_.skipped_rate);
      continue;
    }
    rate.sent(now);
    const FrameInfo& info = borrow.info();

    if (raw_wanted) {
      // The frame's own kind decides the message (a replaced region may have a new layout).
      auto frame_type = ros2::message_type_for(info.layout);
      if (frame_type && raw.ensure(*frame_type)) {
        auto plan = ros2::plan_frame(info, options_.frame_id);
        if (!plan) {
          raw_.count(raw_.failed);
          raw_.problem(options_.stream + ": " + plan.error().message);
        } else {
          OutgoingMessage message{&plan.value(), borrow.bytes().first(info.size), &borrow};
          raw.write(message);
        }
      }
    }
    if (jpeg_wanted && info.layout.kind == LayoutKind::image &&
        imaging::JpegEncoder::encodes(info.layout.image.format)) {
      // Into the encoder's own buffer, from which serializing is the JPEG's one copy.
      auto jpeg = encoder->encode(info.layout.image, borrow.bytes().first(info.size));
      if (!borrow.still_valid()) {  // the encoder read a slot being overwritten: drop its output
        compressed_.count(compressed_.torn);
      } else if (!jpeg) {
        compressed_.count(compressed_.failed);
        compressed_.problem(options_.stream + ": " + jpeg.error().message);
      } else {
        const ros2::Header header{ros2::Time::from_ns(info.stamp_ns), options_.frame_id};
        auto plan = ros2::plan_compressed_image("jpeg", jpeg->size(), header);
        if (plan) {
          OutgoingMessage message{&plan.value(), *jpeg, nullptr};
          compressed->write(message);
        }
      }
    }
  }
}

}  // namespace sim::bridge
