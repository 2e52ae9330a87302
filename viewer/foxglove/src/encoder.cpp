// SPDX-License-Identifier: Apache-2.0
#include "encoder.hpp"

#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"

namespace sim::foxglove {
namespace {

// Images are re-encoded as JPEG only when asked, and only when they are not JPEG already.
bool recompress(const Layout& layout, const EncodeOptions& options) {
  return options.compression == ImageCompression::jpeg && layout.kind == LayoutKind::image &&
         layout.image.format != PixelFormat::mjpeg;
}

}  // namespace

std::optional<MessageSchema> schema_for(const Layout& layout, const EncodeOptions& options) {
  auto type = ros2::message_type_for(layout);
  if (!type) return std::nullopt;
  const ros2::MessageType t = recompress(layout, options) ? ros2::MessageType::compressed_image
                                                          : type.value();
  return MessageSchema{"cdr", std::string(ros2::ros_type_name(t)), "ros2msg",
                       std::string(ros2::ros2msg_schema(t))};
}

FrameEncoder::FrameEncoder(const Layout& layout, const EncodeOptions& options,
                           std::string frame_id)
    : layout_(layout), options_(options), frame_id_(std::move(frame_id)) {}

std::optional<Error> FrameEncoder::encode(std::span<const std::byte> frame, const FrameInfo& info,
                                          std::vector<std::byte>& out) {
  if (!recompress(layout_, options_)) {
    auto plan = ros2::plan_frame(info, frame_id_);
    if (!plan) return plan.error();
    out.resize(plan->size());
    if (plan->write(frame.first(std::min(frame.size(), plan->payload_size())), out) == 0) {
      return Error{ErrorCode::invalid_argument,
                   "a frame of " + std::to_string(frame.size()) +
                       " bytes does not fit its message; the writer's layout may be wrong."};
    }
    return std::nullopt;
  }
  if (!jpeg_) {
    auto jpeg = ImageToJpeg::create(options_.jpeg_quality);
    if (!jpeg) return jpeg.error();
    jpeg_.emplace(std::move(jpeg.value()));
  }
  if (auto error = jpeg_->encode(info.layout.image, frame, compressed_)) {
    return error;
  }
  const ros2::Header header{ros2::Time::from_ns(info.stamp_ns), frame_id_};
  auto plan = ros2::plan_compressed_image("jpeg", compressed_.size(), header);
  if (!plan) return plan.error();
  out.resize(plan->size());
  if (plan->write(compressed_, out) == 0) {
    return Error{ErrorCode::system_error, "the JPEG picture did not fit its message."};
  }
  return std::nullopt;
}

}  // namespace sim::foxglove
