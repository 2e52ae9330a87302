// SPDX-License-Identifier: Apache-2.0
#include "channel_player.hpp"

#include <sys/statvfs.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "sim/ros2/decode.hpp"

namespace sim::play {

namespace {

Error bad(const std::string& sentence) { return Error{ErrorCode::invalid_argument, sentence}; }

bool is_jpeg(std::string_view format) {
  return format.find("jpeg") != std::string_view::npos || format.find("jpg") != std::string_view::npos;
}

// Width and height from a JPEG's headers (libjpeg-turbo reads only the headers).
std::optional<std::pair<std::uint32_t, std::uint32_t>> jpeg_size(std::span<const std::byte> data) {
  tjhandle handle = tjInitDecompress();
  if (handle == nullptr) return std::nullopt;
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  const int rc = tjDecompressHeader3(handle, reinterpret_cast<const unsigned char*>(data.data()),
                                     static_cast<unsigned long>(data.size()), &width, &height,
                                     &subsampling, &colorspace);
  tjDestroy(handle);
  if (rc != 0 || width <= 0 || height <= 0) return std::nullopt;
  return std::make_pair(static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height));
}

// Room for clouds up to twice the first one, rounded to a whole 1024 points.
std::uint64_t room_for_points(std::uint64_t points) { return std::max<std::uint64_t>(1024, (points * 2 + 1023) / 1024 * 1024); }

// The SIM point type a foreign cloud becomes when its bytes are not already one: LiDAR points
// when it has rings, else x y z intensity.
PointType repack_type(const ros2::PointCloud2View& cloud) {
  for (const auto& f : cloud.fields()) {
    if (f.name == "ring" || f.name == "channel") return PointType::lidar_point;
  }
  return PointType::xyzi32;
}

// "255.0": bytes in MiB, for sentences.
std::string mib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", static_cast<double>(bytes) / (1u << 20));
  return text;
}

}  // namespace

std::optional<Error> ShmBudget::take(const std::string& stream, std::uint64_t current,
                                     std::uint64_t needed) {
  if (used_ - std::min(used_, current) + needed > limit_) {
    return bad("stream " + stream + " would take " + mib(needed) + " MiB of shared memory, and the " +
               "recording's streams together may take at most --max-shm " + std::to_string(limit_ >> 20) +
               " MiB; raise it if you trust the recording");
  }
  // The new region exists beside the one it replaces until it is complete: all of it must fit.
  struct statvfs shm {};
  if (statvfs("/dev/shm", &shm) == 0) {
    const std::uint64_t free_bytes = static_cast<std::uint64_t>(shm.f_bavail) * shm.f_frsize;
    if (needed > free_bytes) {
      return bad("stream " + stream + " needs " + mib(needed) + " MiB of /dev/shm but only " +
                 mib(free_bytes) + " MiB are free; remove streams nobody writes (sim_rm --dead) or " +
                 "play fewer topics (--remap, --max-shm)");
    }
  }
  used_ = used_ - std::min(used_, current) + needed;
  return std::nullopt;
}

Expected<ChannelPlayer> ChannelPlayer::for_channel(const mcap::Channel& channel,
                                                   const mcap::Schema* schema, std::string stream,
                                                   std::uint64_t max_capacity, ShmBudget& budget) {
  const std::string topic = mcap::printable(channel.topic);
  if (channel.message_encoding != "cdr") {
    return bad("topic " + topic + " is encoded as \"" + mcap::printable(channel.message_encoding) +
               "\", not ROS 2 CDR; it is skipped");
  }
  const std::string name = schema != nullptr ? schema->name : "";
  std::optional<ros2::MessageType> type;
  for (const auto t : {ros2::MessageType::point_cloud2, ros2::MessageType::image,
                       ros2::MessageType::compressed_image}) {
    // "sensor_msgs/msg/Image" (ROS 2) or "sensor_msgs/Image" (older writers).
    std::string shortened(ros2::ros_type_name(t));
    shortened.erase(shortened.find("/msg/"), 4);
    if (name == ros2::ros_type_name(t) || name == shortened) type = t;
  }
  if (!type) {
    return bad("topic " + topic + " carries " + (name.empty() ? "no schema" : mcap::printable(name)) +
               ", which SIM cannot play (PointCloud2, Image or CompressedImage); it is skipped");
  }
  auto shape = mcap::stream_shape(channel.metadata);
  const auto recorded = channel.metadata.find("sim.stream");
  std::string recorded_stream = recorded == channel.metadata.end() ? channel.topic : recorded->second;
  return ChannelPlayer(*type, topic, std::move(stream), std::move(recorded_stream), shape,
                       max_capacity, budget);
}

std::optional<Error> ChannelPlayer::create_stream() {
  if (!shape_) return bad("the shape of " + stream_ + " is not known yet");
  return ensure_writer(*shape_);
}

std::optional<Error> ChannelPlayer::ensure_writer(const mcap::StreamShape& wanted) {
  if (writer_ && writer_->layout() == wanted.layout && writer_->capacity() == wanted.capacity) {
    return std::nullopt;
  }
  if (wanted.capacity > max_capacity_) {
    return bad("stream " + stream_ + " would need " + std::to_string(wanted.capacity >> 20) +
               " MiB per frame, more than --max-capacity " + std::to_string(max_capacity_ >> 20) +
               " MiB; raise it if you trust the recording");
  }
  const std::uint64_t current = writer_ ? region_size(writer_->capacity()) : 0;
  const std::uint64_t needed = region_size(wanted.capacity);
  if (auto error = budget_->take(stream_, current, needed)) return error;
  writer_.reset();  // a changed shape replaces the region; readers follow
  StreamSpec spec;
  spec.name = stream_;
  spec.layout = wanted.layout;
  spec.capacity = wanted.capacity;
  spec.heartbeat_period = std::chrono::milliseconds(500);
  spec.sensor = sensor_;  // a replaced region keeps the description
  auto created = Writer::create(spec);
  if (!created) {
    budget_->give_back(needed);
    return created.error();
  }
  writer_.emplace(std::move(*created));
  apply_clock();
  made_stream_ = true;
  shape_ = wanted;
  return std::nullopt;
}

std::optional<std::string> ChannelPlayer::bound_by(std::optional<std::span<const std::byte>> first_message) {
  if (!shape_) return std::nullopt;
  const std::uint64_t room = room_for(first_message ? first_message->size() : 0);
  // Beyond --max-capacity the stream is refused anyway, with the sentence naming that option.
  if (shape_->capacity <= room || shape_->capacity > max_capacity_) return std::nullopt;
  if (shape_->layout.kind == LayoutKind::image && shape_->layout.image.format == PixelFormat::mjpeg) {
    // A JPEG stream's capacity is room for one picture of any size (cameras ask two bytes a pixel),
    // not its shape: the pictures it holds tell how much they need, and nothing is wrong.
    shape_->capacity = room;
    return std::nullopt;
  }
  const std::string asked = "topic " + topic_ + " asks for " + mib(shape_->capacity) + " MiB per frame but ";
  const std::string advice = "; check where the file came from (sim_record never writes this)";
  shape_.reset();
  if (!first_message) return asked + "holds no message, so no stream is made for it" + advice;
  (void)learn_shape(*first_message);  // a message that does not decode is said when it is played
  return asked + "its first message holds " + std::to_string(first_message->size()) +
         " bytes, so its stream is sized from its messages instead" + advice;
}

std::optional<Error> ChannelPlayer::learn_shape(std::span<const std::byte> message) {
  if (shape_) return std::nullopt;
  mcap::StreamShape shape;
  switch (type_) {
    case ros2::MessageType::point_cloud2: {
      auto cloud = ros2::decode_point_cloud2(message);
      if (!cloud) return cloud.error();
      auto as_is = ros2::sim_point_layout(*cloud);
      const PointType type = as_is ? as_is->type : repack_type(*cloud);
      shape.layout = Layout::of(PointLayout::of(type, room_for_points(cloud->point_count())));
      break;
    }
    case ros2::MessageType::image: {
      auto image = ros2::decode_image(message);
      if (!image) return image.error();
      auto layout = ros2::sim_image_layout(*image);
      if (!layout) return layout.error();
      shape.layout = Layout::of(*layout);
      break;
    }
    case ros2::MessageType::compressed_image: {
      auto image = ros2::decode_compressed_image(message);
      if (!image) return image.error();
      if (!is_jpeg(image->format)) {
        return bad("topic " + topic_ + " holds \"" + mcap::printable(image->format) +
                   "\" images; SIM plays JPEG only");
      }
      const auto size = jpeg_size(image->data);
      if (!size) return bad("the first image of " + topic_ + " is not a readable JPEG");
      shape.layout = Layout::of(ImageLayout::packed(size->first, size->second, PixelFormat::mjpeg));
      shape.capacity = std::max<std::uint64_t>(kRoomFloor, image->data.size() * 4);
      break;
    }
  }
  if (shape.capacity == 0) shape.capacity = shape.layout.min_capacity();
  shape_ = shape;
  return std::nullopt;
}

std::optional<Error> ChannelPlayer::play(std::span<const std::byte> message, std::int64_t stamp_shift_ns) {
  if (!shape_) {
    if (auto error = learn_shape(message)) return error;
  }
  // Decode first, settle the stream's shape, then loan the slot once and fill it.
  auto does_not_fit = [&] { return bad("a frame of " + topic_ + " does not fit stream " + stream_); };
  switch (type_) {
    case ros2::MessageType::point_cloud2: {
      auto cloud = ros2::decode_point_cloud2(message);
      if (!cloud) return cloud.error();
      mcap::StreamShape wanted = *shape_;
      if (cloud->point_count() > wanted.layout.points.max_points) {  // larger than any before: grow
        wanted.layout.points.max_points = room_for_points(cloud->point_count());
        wanted.capacity = wanted.layout.min_capacity();
      }
      if (auto error = ensure_writer(wanted)) return error;
      Loan loan = writer_->loan();
      const PointLayout& points = wanted.layout.points;
      std::uint64_t size = 0;
      auto as_is = ros2::sim_point_layout(*cloud);
      if (!loan.valid()) return does_not_fit();
      if (as_is && as_is->type == points.type) {
        if (loan.bytes().size() < cloud->data.size()) return does_not_fit();
        std::memcpy(loan.bytes().data(), cloud->data.data(), cloud->data.size());
        size = cloud->data.size();
      } else {
        auto n = ros2::repack_points(*cloud, points.type, loan.bytes());
        if (!n) return n.error();
        size = *n * points.point_size;
      }
      update_sensor(cloud->header.frame_id);
      return commit(std::move(loan), size, cloud->header.stamp.to_ns() + stamp_shift_ns);
    }
    case ros2::MessageType::image: {
      auto image = ros2::decode_image(message);
      if (!image) return image.error();
      auto layout = ros2::sim_image_layout(*image);
      if (!layout) return layout.error();
      mcap::StreamShape wanted = *shape_;
      if (!(*layout == wanted.layout.image)) {  // the camera changed its format: follow it
        wanted = {Layout::of(*layout), layout->frame_bytes()};
      }
      if (auto error = ensure_writer(wanted)) return error;
      Loan loan = writer_->loan();
      if (!loan.valid() || loan.bytes().size() < image->data.size()) return does_not_fit();
      std::memcpy(loan.bytes().data(), image->data.data(), image->data.size());
      update_sensor(image->header.frame_id);
      return commit(std::move(loan), image->data.size(), image->header.stamp.to_ns() + stamp_shift_ns);
    }
    case ros2::MessageType::compressed_image: {
      auto image = ros2::decode_compressed_image(message);
      if (!image) return image.error();
      mcap::StreamShape wanted = *shape_;
      if (image->data.size() > wanted.capacity) wanted.capacity = image->data.size() * 2;
      if (auto error = ensure_writer(wanted)) return error;
      Loan loan = writer_->loan();
      if (!loan.valid() || loan.bytes().size() < image->data.size()) return does_not_fit();
      std::memcpy(loan.bytes().data(), image->data.data(), image->data.size());
      update_sensor(image->header.frame_id);
      return commit(std::move(loan), image->data.size(), image->header.stamp.to_ns() + stamp_shift_ns);
    }
  }
  return bad("unknown message type");
}

void ChannelPlayer::set_calibration(const CameraCalibration& calibration) {
  if (calibration_ && *calibration_ == calibration) return;
  calibration_ = calibration;
  sensor_dirty_ = true;
  // rosbag2 logs a CameraInfo after its image: the stream has it now, not one frame later.
  if (writer_ && !frame_id_.empty()) update_sensor(frame_id_);
}

void ChannelPlayer::set_clock(const ClockStatus& clock) {
  if (clock_ && *clock_ == clock) return;
  clock_ = clock;
  apply_clock();
}

void ChannelPlayer::apply_clock() {
  if (!writer_ || !clock_) return;
  auto set = writer_->set_clock(*clock_);
  if (!set && sensor_problem_.empty()) {
    sensor_problem_ = "the clock record of " + stream_ + " is not restored: " + set.error().message;
  }
}

void ChannelPlayer::update_sensor(std::string_view frame_id) {
  if (frame_id != frame_id_) {  // one comparison per frame; a copy only when it changes
    frame_id_ = frame_id;
    sensor_dirty_ = true;
  }
  if (mountings_ != nullptr && mountings_->generation != mountings_seen_) {
    mountings_seen_ = mountings_->generation;
    sensor_dirty_ = true;
  }
  if (!sensor_dirty_ || !writer_) return;
  sensor_dirty_ = false;
  SensorInfo info;
  info.frame_id = frame_id_;
  info.calibration = calibration_;
  if (mountings_ != nullptr) {
    if (const auto it = mountings_->to_root.find(frame_id_); it != mountings_->to_root.end()) {
      info.parent_frame = it->second.first;
      info.mounting = it->second.second;
    }
  }
  // Review turn 4 M2: an uncalibrated camera's CameraInfo (K all zero) loses only its calibration.
  const std::string dropped = drop_unusable_parts(info);
  if (!dropped.empty() && sensor_problem_.empty()) {
    sensor_problem_ = "the sensor description of " + stream_ + " is restored in part: " + dropped;
  }
  if (!info.calibration && !info.mounting) return;  // the recording says nothing about it
  if (sensor_ && *sensor_ == info) return;
  const std::string problem = sensor_info_problem(info);
  auto set = problem.empty() ? writer_->set_sensor_info(info) : Expected<void>(Error{ErrorCode::invalid_argument, problem});
  if (!set) {
    if (sensor_problem_.empty()) {
      sensor_problem_ = "the sensor description of " + stream_ + " is not restored: " + set.error().message;
    }
    return;
  }
  sensor_ = std::move(info);
}

std::optional<Error> ChannelPlayer::commit(Loan&& loan, std::uint64_t size, std::int64_t stamp_ns) {
  if (std::move(loan).commit(size, stamp_ns) != WriteStatus::ok) {
    return bad("a frame of " + topic_ + " could not be published to stream " + stream_);
  }
  ++frames_;
  return std::nullopt;
}

}  // namespace sim::play
