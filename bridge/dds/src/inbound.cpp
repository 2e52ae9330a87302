// SPDX-License-Identifier: Apache-2.0
#include "inbound.hpp"

#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "sim/imaging/jpeg_encoder.hpp"
#include "sim/ros2/decode.hpp"

namespace sim::bridge {

namespace dds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

namespace {
constexpr auto discovery_poll = 100ms;
constexpr std::uint64_t min_point_capacity = 4096;     // points, before growth
constexpr std::uint64_t min_jpeg_capacity = 1 << 20;   // bytes, before growth
// More points than any LiDAR makes in one frame (a 128-channel dual-return sensor at 10 Hz makes
// under 1 M): a cloud claiming more is refused rather than sizing a huge region for it.
constexpr std::uint64_t max_cloud_points = 8'000'000;

bool is_jpeg_format(std::string_view format) {
  // "jpeg", "bgr8; jpeg compressed bgr8" (image_transport), "jpg".
  return format.find("jpeg") != std::string_view::npos || format.find("jpg") != std::string_view::npos;
}
}  // namespace

Inbound::Inbound(DdsSession& session, InboundOptions options)
    : session_(session), options_(std::move(options)) {
  if (options_.stream.empty()) options_.stream = options_.topic;
  thread_ = std::thread([this] { run(); });
}

Inbound::~Inbound() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void Inbound::run() {
  const std::string dds_topic = ros2::dds_topic_name(options_.topic);
  std::optional<ros2::MessageType> type;
  while (!stop_.load() && !(type = session_.discovered_type(dds_topic))) {
    std::this_thread::sleep_for(discovery_poll);
  }
  if (!type) return;
  type_ = *type;
  std::string error;
  dds::DataReader* reader = session_.create_reader(dds_topic, type_, options_.qos, error);
  if (reader == nullptr) {
    counters_.problem(error);
    return;
  }
  counters_.connected.store(true);
  IncomingMessage sample{this};
  dds::SampleInfo info;
  while (!stop_.load(std::memory_order_relaxed)) {
    dds::SubscriptionMatchedStatus matched;
    reader->get_subscription_matched_status(matched);
    counters_.matched.store(matched.current_count, std::memory_order_relaxed);
    if (!reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0, 100'000'000))) continue;
    // deliver() runs inside take_next_sample(), while Fast DDS holds the received bytes.
    while (!stop_.load(std::memory_order_relaxed) &&
           reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
    }
  }
  session_.delete_reader(reader);
}

void Inbound::deliver(std::span<const std::byte> message) {
  counters_.count(counters_.frames_seen);
  switch (type_) {
    case ros2::MessageType::image: deliver_image(message); break;
    case ros2::MessageType::compressed_image: deliver_compressed(message); break;
    case ros2::MessageType::point_cloud2: deliver_cloud(message); break;
  }
}

void Inbound::drop(const std::string& sentence) {
  counters_.count(counters_.malformed);
  counters_.problem(options_.topic + ": " + sentence);
}

Writer* Inbound::writer_for(const Layout& layout, std::uint64_t bytes, std::uint64_t capacity) {
  if (writer_ && writer_->layout() == layout && writer_->capacity() >= bytes) return &*writer_;
  writer_.reset();  // our own lock goes first, so the new writer may replace the region
  StreamSpec spec;
  spec.name = options_.stream;
  spec.layout = layout;
  spec.capacity = capacity;
  auto created = Writer::create(spec);
  if (!created) {
    counters_.count(counters_.failed);
    counters_.problem(options_.stream + ": " + created.error().message);
    return nullptr;
  }
  writer_.emplace(std::move(created.value()));
  return &*writer_;
}

void Inbound::deliver_image(std::span<const std::byte> message) {
  auto view = ros2::decode_image(message);
  if (!view) return drop(view.error().message);
  auto layout = ros2::sim_image_layout(*view);
  if (!layout) return drop(layout.error().message);
  Writer* writer = writer_for(Layout::of(*layout), view->data.size(), layout->frame_bytes());
  if (writer == nullptr) return;
  Loan loan = writer->loan();
  std::memcpy(loan.bytes().data(), view->data.data(), view->data.size());  // the one copy
  if (std::move(loan).commit(view->data.size(), view->header.stamp.to_ns()) == WriteStatus::ok) {
    counters_.count(counters_.bridged);
  } else {
    counters_.count(counters_.failed);
  }
}

void Inbound::deliver_compressed(std::span<const std::byte> message) {
  auto view = ros2::decode_compressed_image(message);
  if (!view) return drop(view.error().message);
  if (!is_jpeg_format(view->format)) {
    return drop("CompressedImage format '" + std::string(view->format) +
                "' is not JPEG; only JPEG becomes an mjpeg SIM stream");
  }
  auto size = imaging::read_jpeg_size(view->data);
  if (!size) return drop("the CompressedImage data: " + size.error().message);
  const ImageLayout image{size->width, size->height, 3, 0, PixelFormat::mjpeg, 8};
  // A JPEG's size varies per frame: keep slots at twice the largest seen so far.
  std::uint64_t capacity = std::max<std::uint64_t>(min_jpeg_capacity, 2 * view->data.size());
  if (writer_ && writer_->layout() == Layout::of(image)) {
    capacity = std::max(capacity, writer_->capacity());
  }
  Writer* writer = writer_for(Layout::of(image), view->data.size(), capacity);
  if (writer == nullptr) return;
  Loan loan = writer->loan();
  std::memcpy(loan.bytes().data(), view->data.data(), view->data.size());
  if (std::move(loan).commit(view->data.size(), view->header.stamp.to_ns()) == WriteStatus::ok) {
    counters_.count(counters_.bridged);
  } else {
    counters_.count(counters_.failed);
  }
}

void Inbound::deliver_cloud(std::span<const std::byte> message) {
  auto view = ros2::decode_point_cloud2(message);
  if (!view) return drop(view.error().message);
  // Clouds that already are SIM points are copied as they are; others are converted.
  auto exact = ros2::sim_point_layout(*view);
  const PointType type = exact ? exact->type : PointType::lidar_point;
  const std::uint64_t points = view->point_count();
  if (points > max_cloud_points) {
    return drop("a cloud of " + std::to_string(points) + " points is more than the " +
                std::to_string(max_cloud_points) + " a SIM stream takes");
  }
  const std::uint64_t bytes = points * point_size(type);
  // The point count varies per revolution: size the slots for twice the largest cloud so far.
  std::uint64_t max_points = std::max<std::uint64_t>(min_point_capacity, 2 * points);
  if (writer_ && writer_->layout().kind == LayoutKind::points &&
      writer_->layout().points.type == type) {
    max_points = std::max(max_points, writer_->layout().points.max_points);
  }
  const Layout layout = Layout::of(PointLayout::of(type, max_points));
  Writer* writer = writer_for(layout, bytes, layout.min_capacity());
  if (writer == nullptr) return;
  Loan loan = writer->loan();
  if (exact) {
    std::memcpy(loan.bytes().data(), view->data.data(), bytes);
  } else {
    auto written = ros2::repack_points(*view, type, loan.bytes());
    if (!written) return drop(written.error().message);  // the loan is dropped unpublished
  }
  if (std::move(loan).commit(bytes, view->header.stamp.to_ns()) == WriteStatus::ok) {
    counters_.count(counters_.bridged);
  } else {
    counters_.count(counters_.failed);
  }
}

}  // namespace sim::bridge
