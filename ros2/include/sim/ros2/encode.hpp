// SPDX-License-Identifier: Apache-2.0
// Serializing a SIM frame as a ROS 2 message with at most one copy of its bytes.
//
// A message is a small prefix (encapsulation, header, sizes, field list, the data length), the
// frame's bytes unchanged, and a small suffix (PointCloud2's is_dense). plan_*() computes the
// prefix and suffix without touching the frame; write() then copies prefix + frame + suffix into
// a buffer the caller owns (a DDS SerializedPayload, an MCAP chunk, a WebSocket frame), or a
// caller that can gather sends prefix(), the frame and suffix() as they are.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sim/layout.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"
#include "sim/ros2/message.hpp"

namespace sim::ros2 {

// Longest frame_id a plan accepts; ROS frame ids are short names such as "lidar_top".
inline constexpr std::size_t max_frame_id_length = 255;

class MessagePlan {
 public:
  MessageType type() const noexcept { return type_; }
  // Bytes of the whole serialized message, the 4-byte encapsulation header included.
  std::size_t size() const noexcept { return prefix_size_ + payload_size_ + suffix_size_; }
  std::span<const std::byte> prefix() const noexcept { return {prefix_.data(), prefix_size_}; }
  // Bytes of the frame that go between prefix and suffix, and where they start in the message.
  std::size_t payload_size() const noexcept { return payload_size_; }
  std::size_t payload_offset() const noexcept { return prefix_size_; }
  std::span<const std::byte> suffix() const noexcept { return {suffix_.data(), suffix_size_}; }

  // Writes the message into out[0, size()): the one copy of the frame's bytes. Returns size(), or
  // 0 (writing nothing) when out is shorter than size() or payload is not payload_size() long.
  std::size_t write(std::span<const std::byte> payload, std::span<std::byte> out) const noexcept;

 private:
  friend struct PlanBuilder;
  static constexpr std::size_t max_prefix = 1024;
  MessageType type_ = MessageType::image;
  std::array<std::byte, max_prefix> prefix_{};
  std::size_t prefix_size_ = 0;
  std::size_t payload_size_ = 0;
  std::array<std::byte, 4> suffix_{};
  std::size_t suffix_size_ = 0;
};

// PointCloud2 of `bytes` bytes of points (a multiple of the point size): height 1, width = the
// point count, the fields of point_fields(), is_dense false (SIM does not promise no NaNs).
Expected<MessagePlan> plan_point_cloud2(const PointLayout& layout, std::uint64_t bytes,
                                        const Header& header);
// Image of a packed SIM image frame: bytes must be stride × height.
Expected<MessagePlan> plan_image(const ImageLayout& layout, std::uint64_t bytes,
                                 const Header& header);
// CompressedImage of `bytes` bytes of an encoded picture; format e.g. "jpeg" or "png".
Expected<MessagePlan> plan_compressed_image(std::string_view format, std::uint64_t bytes,
                                            const Header& header);
// The message of a SIM frame as message_type_for() picks it (mjpeg frames as "jpeg"), stamped
// with the frame's sensor time.
Expected<MessagePlan> plan_frame(const FrameInfo& info, std::string_view frame_id);

}  // namespace sim::ros2
