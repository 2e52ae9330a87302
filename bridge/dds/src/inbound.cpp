// SPDX-License-Identifier: Apache-2.0
#include "inbound.hpp"

#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "sim/clock.hpp"
#include "sim/imaging/jpeg_encoder.hpp"
#include "sim/ros2/decode.hpp"
#include "sim/ros2/metadata.hpp"

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
// Review M3: a repacked cloud may take at most this many times the bytes its message carried
// (real clouds have 12-byte xyz or more per point, so 24-byte SIM points are at most twice).
constexpr std::uint64_t max_cloud_growth = 4;
constexpr std::uint64_t small_cloud_bytes = 1 << 20;  // below this the growth does not matter

bool is_jpeg_format(std::string_view format) {
  // "jpeg", "bgr8; jpeg compressed bgr8" (image_transport), "jpg".
  return format.find("jpeg") != std::string_view::npos || format.find("jpg") != std::string_view::npos;
}

bool same_calibration(const CameraCalibration& a, const CameraCalibration& b) {
  // Field by field: GCC 12 emits no body for CameraCalibration's defaulted operator==.
  return a.width == b.width && a.height == b.height && a.distortion_model == b.distortion_model &&
         a.d == b.d && a.k == b.k && a.r == b.r && a.p == b.p && a.binning_x == b.binning_x &&
         a.binning_y == b.binning_y && a.roi.x_offset == b.roi.x_offset &&
         a.roi.y_offset == b.roi.y_offset && a.roi.width == b.roi.width &&
         a.roi.height == b.roi.height && a.roi.do_rectify == b.roi.do_rectify;
}

bool same_sensor(const std::optional<SensorInfo>& a, const SensorInfo& b) {
  if (!a || a->frame_id != b.frame_id || a->parent_frame != b.parent_frame ||
      a->mounting != b.mounting || a->calibration.has_value() != b.calibration.has_value()) {
    return false;
  }
  return !a->calibration || same_calibration(*a->calibration, *b.calibration);
}
}  // namespace

Inbound::Inbound(DdsSession& session, RemoteTransforms& transforms, InboundOptions options)
    : session_(session), transforms_(transforms), options_(std::move(options)) {
  if (options_.stream.empty()) options_.stream = options_.topic;
  camera_info_sink_.inbound = this;
  thread_ = std::thread([this] { run(); });
}

Inbound::~Inbound() { stop(); }

void Inbound::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

// Takes every waiting sample; the bridge's own messages are taken unread (review H1).
void Inbound::take_all(dds::DataReader* reader, MessageSink* sink) {
  IncomingMessage sample{sink};
  IncomingMessage ignored{nullptr};
  dds::SampleInfo info;
  // deliver() runs inside take_next_sample(), while Fast DDS holds the received bytes.
  while (!stop_.load(std::memory_order_relaxed) &&
         reader->get_first_untaken_info(&info) == ReturnCode_t::RETCODE_OK) {
    if (reader->take_next_sample(session_.own_sample(info) ? &ignored : &sample, &info) !=
        ReturnCode_t::RETCODE_OK) {
      break;
    }
  }
}

// Review M4 and L8: remote writers discovery announced that cannot be read are told why.
void Inbound::tell_mismatches(const std::string& dds_topic) {
  for (const RemoteEndpoint& w : session_.remote_writers(dds_topic)) {
    if (w.type_name != ros2::dds_type_name(type_)) {
      counters_.problem(options_.topic + ": a writer publishes " + w.type_name + ", but this "
                        "subscription reads " + std::string(ros2::dds_type_name(type_)) +
                        " (its first writer's type); restart the bridge to follow the new type");
    } else if (!w.reliable && options_.qos.reliable) {
      counters_.problem(options_.topic + ": a writer publishes best effort and does not match "
                        "--reliable-subscribe; leave that option out to read it");
    } else if (!w.xcdr1) {
      counters_.problem(options_.topic + ": a writer sends only XCDR2 data; ROS 2 nodes and the "
                        "bridge use XCDR1, so it is not read");
    }
  }
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
  dds::DataReader* reader = session_.create_reader(dds_topic, ros2::dds_type_name(type_), options_.qos, error);
  if (reader == nullptr) {
    counters_.problem(error);
    return;
  }
  dds::DataReader* camera_info = nullptr;
  if (type_ != ros2::MessageType::point_cloud2) {
    camera_info = session_.create_reader(ros2::dds_topic_name(ros2::camera_info_topic_for(options_.topic)),
                                         ros2::camera_info_dds_type_name, options_.qos, error);
    if (camera_info == nullptr) counters_.problem(error);
  }
  counters_.connected.store(true);
  std::int64_t next_mismatch_check_ns = 0;
  while (!stop_.load(std::memory_order_relaxed)) {
    dds::SubscriptionMatchedStatus matched;
    reader->get_subscription_matched_status(matched);
    counters_.matched.store(matched.current_count, std::memory_order_relaxed);
    if (const std::int64_t now = monotonic_ns(); now >= next_mismatch_check_ns) {
      next_mismatch_check_ns = now + 500'000'000;  // twice a second, not per message
      tell_mismatches(dds_topic);
    }
    if (camera_info != nullptr) take_all(camera_info, &camera_info_sink_);
    if (!reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0, 100'000'000))) continue;
    take_all(reader, this);
  }
  session_.delete_reader(camera_info);
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

void Inbound::CameraInfoSink::deliver(std::span<const std::byte> message) {
  auto info = ros2::decode_camera_info(message);
  if (!info) {
    inbound->counters_.problem(ros2::camera_info_topic_for(inbound->options_.topic) + ": " +
                               info.error().message);
    return;
  }
  if (inbound->calibration_ && same_calibration(*inbound->calibration_, info->calibration)) return;
  inbound->calibration_ = std::move(info->calibration);
  inbound->update_sensor();
}

void Inbound::update_sensor() {
  if (!writer_ || frame_id_.empty()) return;
  SensorInfo sensor;
  sensor.frame_id = frame_id_;
  sensor.calibration = calibration_;
  if (auto parent = transforms_.mounting_of(frame_id_)) {
    sensor.parent_frame = parent->frame;
    sensor.mounting = parent->mounting;
  }
  if (same_sensor(offered_, sensor)) return;  // told once, not retried per frame
  offered_ = sensor;
  // Review turn 4 M2: a part that cannot be used (an uncalibrated camera's all-zero K) goes
  // alone; the frame and the mounting stay.
  if (const std::string dropped = drop_unusable_parts(sensor); !dropped.empty()) {
    counters_.problem(options_.stream + ": the sensor description from ROS 2: " + dropped);
  }
  if (!sensor.mounting && !sensor.calibration) return;  // nothing worth describing
  if (same_sensor(sensor_, sensor)) return;
  if (auto set = writer_->set_sensor_info(sensor); !set) {
    counters_.problem(options_.stream + ": the sensor description from ROS 2 is refused: " +
                      set.error().message);
    return;  // review turn 4 M1: sensor_ (what a replaced region gets) holds only what was set
  }
  sensor_ = std::move(sensor);
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
  spec.sensor = sensor_;  // the new region keeps the description
  auto created = Writer::create(spec);
  if (!created) {
    counters_.count(counters_.failed);
    counters_.problem(options_.stream + ": " + created.error().message);
    return nullptr;
  }
  writer_.emplace(std::move(created.value()));
  return &*writer_;
}

template <typename Fill>
void Inbound::publish(Writer& writer, std::uint64_t bytes, std::int64_t stamp_ns, Fill&& fill) {
  Loan loan = writer.loan();
  fill(loan.bytes());  // the one copy
  if (std::move(loan).commit(bytes, stamp_ns) == WriteStatus::ok) {
    counters_.count(counters_.bridged);
  } else {
    counters_.count(counters_.failed);
  }
  // /tf_static may bring the mounting later: looked at when the frame changes, else once a second.
  const std::int64_t now = monotonic_ns();
  if (sensor_check_due_ || now >= next_sensor_check_ns_) {
    sensor_check_due_ = false;
    next_sensor_check_ns_ = now + 1'000'000'000;
    update_sensor();
  }
}

void Inbound::note_frame_id(std::string_view frame_id) {
  if (frame_id == frame_id_) return;
  frame_id_.assign(frame_id);
  sensor_check_due_ = true;
}

namespace {
// Review L7: a stamp before 1970 is no sensor time; the message is dropped with this sentence.
std::string stamp_problem(const ros2::Header& header) {
  if (header.stamp.sec >= 0) return {};
  return "its header.stamp is " + std::to_string(header.stamp.sec) +
         " s, before 1970; publish the acquisition time";
}
}  // namespace

void Inbound::deliver_image(std::span<const std::byte> message) {
  auto view = ros2::decode_image(message);
  if (!view) return drop(view.error().message);
  if (auto why = stamp_problem(view->header); !why.empty()) return drop(why);
  auto layout = ros2::sim_image_layout(*view);
  if (!layout) return drop(layout.error().message);
  Writer* writer = writer_for(Layout::of(*layout), view->data.size(), layout->frame_bytes());
  if (writer == nullptr) return;
  note_frame_id(view->header.frame_id);
  publish(*writer, view->data.size(), view->header.stamp.to_ns(), [&](std::span<std::byte> out) {
    std::memcpy(out.data(), view->data.data(), view->data.size());
  });
}

void Inbound::deliver_compressed(std::span<const std::byte> message) {
  auto view = ros2::decode_compressed_image(message);
  if (!view) return drop(view.error().message);
  if (auto why = stamp_problem(view->header); !why.empty()) return drop(why);
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
  note_frame_id(view->header.frame_id);
  publish(*writer, view->data.size(), view->header.stamp.to_ns(), [&](std::span<std::byte> out) {
    std::memcpy(out.data(), view->data.data(), view->data.size());
  });
}

void Inbound::deliver_cloud(std::span<const std::byte> message) {
  auto view = ros2::decode_point_cloud2(message);
  if (!view) return drop(view.error().message);
  if (auto why = stamp_problem(view->header); !why.empty()) return drop(why);
  // Clouds that already are SIM points are copied as they are; others are converted, and every
  // check the conversion makes runs before the stream is touched (review M2).
  auto exact = ros2::sim_point_layout(*view);
  if (!exact) {
    if (auto why = ros2::repack_problem(*view); !why.empty()) return drop(why);
  }
  const PointType type = exact ? exact->type : PointType::lidar_point;
  const std::uint64_t points = view->point_count();
  if (points > max_cloud_points) {
    return drop("a cloud of " + std::to_string(points) + " points is more than the " +
                std::to_string(max_cloud_points) + " a SIM stream takes");
  }
  const std::uint64_t bytes = points * point_size(type);
  if (bytes > std::max<std::uint64_t>(small_cloud_bytes, max_cloud_growth * view->data.size())) {
    return drop("a cloud of " + std::to_string(points) + " points of " +
                std::to_string(view->point_step) + " bytes would take " + std::to_string(bytes) +
                " bytes as SIM points, more than " + std::to_string(max_cloud_growth) +
                " times the message; publish FLOAT32 x, y and z");
  }
  // The point count varies per revolution: size the slots for twice the largest cloud so far.
  std::uint64_t max_points = std::max<std::uint64_t>(min_point_capacity, 2 * points);
  if (writer_ && writer_->layout().kind == LayoutKind::points &&
      writer_->layout().points.type == type) {
    max_points = std::max(max_points, writer_->layout().points.max_points);
  }
  const Layout layout = Layout::of(PointLayout::of(type, max_points));
  Writer* writer = writer_for(layout, bytes, layout.min_capacity());
  if (writer == nullptr) return;
  note_frame_id(view->header.frame_id);
  publish(*writer, bytes, view->header.stamp.to_ns(), [&](std::span<std::byte> out) {
    if (exact) {
      std::memcpy(out.data(), view->data.data(), bytes);
    } else {
      (void)ros2::repack_points(*view, type, out);  // checked above: it converts every point
    }
  });
}

}  // namespace sim::bridge
