// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/encode.hpp"

#include <cstring>
#include <optional>
#include <limits>
#include <string>

#include "cdr.hpp"
#include "wire.hpp"

namespace sim::ros2 {

namespace {

using wire::invalid;


std::optional<Error> check_payload(std::uint64_t bytes) {
  if (bytes > std::numeric_limits<std::uint32_t>::max()) {
    return invalid("a frame of " + std::to_string(bytes) +
                   " bytes is larger than a ROS 2 message can carry (4 GiB)");
  }
  return std::nullopt;
}

using wire::write_header;

}  // namespace

// Fills a plan's prefix through a CDR writer; the only code that touches MessagePlan's insides.
struct PlanBuilder {
  MessagePlan plan;
  cdr::Writer w;
  explicit PlanBuilder(MessageType type) : w(plan.prefix_) { plan.type_ = type; }
  MessagePlan finish(std::uint64_t payload, std::span<const std::byte> suffix) {
    plan.prefix_size_ = w.size();
    plan.payload_size_ = static_cast<std::size_t>(payload);
    if (!suffix.empty()) std::memcpy(plan.suffix_.data(), suffix.data(), suffix.size());
    plan.suffix_size_ = suffix.size();
    return plan;
  }
};

std::size_t MessagePlan::write(std::span<const std::byte> payload,
                               std::span<std::byte> out) const noexcept {
  if (out.size() < size() || payload.size() != payload_size_) return 0;
  std::byte* p = out.data();
  std::memcpy(p, prefix_.data(), prefix_size_);
  p += prefix_size_;
  if (payload_size_ != 0) std::memcpy(p, payload.data(), payload_size_);
  p += payload_size_;
  if (suffix_size_ != 0) std::memcpy(p, suffix_.data(), suffix_size_);
  return size();
}

Expected<MessagePlan> plan_point_cloud2(const PointLayout& layout, std::uint64_t bytes,
                                        const Header& header) {
  if (auto e = wire::header_problem(header)) return *e;
  if (auto e = check_payload(bytes)) return *e;
  const std::span<const PointField> fields = point_fields(layout.type);
  if (fields.empty() || layout.point_size != point_size(layout.type)) {
    return invalid("the point layout is not one SIM publishes as PointCloud2 (xyz32, xyzi32 or "
                   "lidar_point)");
  }
  if (bytes % layout.point_size != 0) {
    return invalid("a frame of " + std::to_string(bytes) + " bytes is not a whole number of " +
                   std::to_string(layout.point_size) + "-byte points");
  }
  PlanBuilder b(MessageType::point_cloud2);
  write_header(b.w, header);
  b.w.u32(1);                                                    // height: unorganized cloud
  b.w.u32(static_cast<std::uint32_t>(bytes / layout.point_size));  // width: the point count
  b.w.u32(static_cast<std::uint32_t>(fields.size()));
  for (const PointField& f : fields) {
    b.w.string(f.name);
    b.w.u32(f.offset);
    b.w.u8(f.datatype);
    b.w.u32(f.count);
  }
  b.w.u8(0);  // is_bigendian
  b.w.u32(layout.point_size);
  b.w.u32(static_cast<std::uint32_t>(bytes));  // row_step: the one row
  b.w.u32(static_cast<std::uint32_t>(bytes));  // data length
  const std::byte is_dense[1] = {std::byte{0}};
  return b.finish(bytes, is_dense);
}

Expected<MessagePlan> plan_image(const ImageLayout& layout, std::uint64_t bytes,
                                 const Header& header) {
  if (auto e = wire::header_problem(header)) return *e;
  if (auto e = check_payload(bytes)) return *e;
  const std::string_view encoding = ros_encoding(layout.format);
  if (encoding.empty()) {
    return invalid(std::string("pixel format ") + to_string(layout.format) +
                   " has no ROS Image encoding" +
                   (layout.format == PixelFormat::mjpeg ? "; publish it as a CompressedImage" : ""));
  }
  if (bytes != layout.frame_bytes() || layout.stride < std::uint64_t{layout.width} *
                                                           bytes_per_pixel(layout.format)) {
    return invalid("an image frame of " + std::to_string(bytes) + " bytes does not match its " +
                   std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                   " layout with stride " + std::to_string(layout.stride));
  }
  PlanBuilder b(MessageType::image);
  write_header(b.w, header);
  b.w.u32(layout.height);
  b.w.u32(layout.width);
  b.w.string(encoding);
  b.w.u8(0);  // is_bigendian: SIM's 16-bit pixels are little endian
  b.w.u32(layout.stride);
  b.w.u32(static_cast<std::uint32_t>(bytes));
  return b.finish(bytes, {});
}

Expected<MessagePlan> plan_compressed_image(std::string_view format, std::uint64_t bytes,
                                            const Header& header) {
  if (auto e = wire::header_problem(header)) return *e;
  if (auto e = check_payload(bytes)) return *e;
  if (format.size() > max_frame_id_length || format.find('\0') != std::string_view::npos) {
    return invalid("the CompressedImage format must be a short name such as jpeg");
  }
  PlanBuilder b(MessageType::compressed_image);
  write_header(b.w, header);
  b.w.string(format);
  b.w.u32(static_cast<std::uint32_t>(bytes));
  return b.finish(bytes, {});
}

Expected<MessagePlan> plan_frame(const FrameInfo& info, std::string_view frame_id) {
  const Header header{Time::from_ns(info.stamp_ns), frame_id};
  auto type = message_type_for(info.layout);
  if (!type) return type.error();
  switch (*type) {
    case MessageType::point_cloud2: return plan_point_cloud2(info.layout.points, info.size, header);
    case MessageType::image: return plan_image(info.layout.image, info.size, header);
    case MessageType::compressed_image: return plan_compressed_image("jpeg", info.size, header);
  }
  return invalid("unknown message type");
}

}  // namespace sim::ros2
