// SPDX-License-Identifier: Apache-2.0
// Parsing ROS 2 messages from the network into views, so a subscriber copies the data once,
// straight into a loaned SIM slot.
//
// Every length is checked against the buffer and against the other fields (an Image's data must
// be step × height bytes, a PointCloud2's row_step × height): bad input yields an Error with one
// sentence, never a read outside the buffer. Views borrow the message bytes: keep them alive.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "sim/layout.hpp"
#include "sim/result.hpp"
#include "sim/ros2/message.hpp"

namespace sim::ros2 {

struct ImageView {
  Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string_view encoding;
  bool is_bigendian = false;
  std::uint32_t step = 0;
  std::span<const std::byte> data;  // exactly step × height bytes
};

struct CompressedImageView {
  Header header;
  std::string_view format;
  std::span<const std::byte> data;
};

// Most fields a PointCloud2 may declare here (Autoware's richest point type has 10).
inline constexpr std::size_t max_point_fields = 32;

struct PointCloud2View {
  Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::array<PointField, max_point_fields> field_storage{};
  std::size_t field_count = 0;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::span<const std::byte> data;  // exactly row_step × height bytes
  bool is_dense = false;

  std::span<const PointField> fields() const noexcept { return {field_storage.data(), field_count}; }
  std::uint64_t point_count() const noexcept { return std::uint64_t{width} * height; }
};

// The whole serialized message, encapsulation header first (XCDR1 little endian, 00 01 00 00).
Expected<ImageView> decode_image(std::span<const std::byte> message);
Expected<CompressedImageView> decode_compressed_image(std::span<const std::byte> message);
Expected<PointCloud2View> decode_point_cloud2(std::span<const std::byte> message);

// The SIM layout of a decoded image, whose data is then exactly one SIM frame: the encoding must
// be one SIM knows and 16-bit pixels little endian.
Expected<ImageLayout> sim_image_layout(const ImageView& image);

// The SIM point type whose bytes the cloud's data already is (same fields at the same offsets,
// point_step equal to the SIM point size, rows packed), so it can be copied as it is; otherwise
// an error saying so (then repack_points() converts it).
Expected<PointLayout> sim_point_layout(const PointCloud2View& cloud);

// Why repack_points() cannot convert `cloud` (big endian, or no x, y and z field), or empty when
// it can: what a subscriber checks before it touches its SIM stream.
std::string repack_problem(const PointCloud2View& cloud);

// Converts any cloud with FLOAT32 or FLOAT64 x, y, z into SIM points of `type`, one point per
// cloud point in order: intensity from any numeric "intensity" field, for lidar_point also
// ring ("ring" or "channel"), return_index ("return_type"), time_offset_ns ("time_stamp" or "t"
// in ns); absent fields become 0. Writes min(point_count, out capacity) points and returns how
// many; an error when x, y or z is missing or a field lies outside point_step.
Expected<std::uint64_t> repack_points(const PointCloud2View& cloud, PointType type,
                                      std::span<std::byte> out);

}  // namespace sim::ros2
