// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/decode.hpp"

#include <algorithm>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>

#include "cdr.hpp"
#include "wire.hpp"
#include "sim/lidar_point.hpp"

namespace sim::ros2 {

namespace {

using wire::malformed;

using wire::read_failure;
using wire::read_header;

std::string dims(std::uint64_t a, std::uint64_t b) {
  return std::to_string(a) + " x " + std::to_string(b);
}

}  // namespace

Expected<ImageView> decode_image(std::span<const std::byte> message) {
  constexpr auto type = MessageType::image;
  cdr::Reader r(message);
  ImageView v;
  if (r.encapsulation()) {
    v.header = read_header(r);
    v.height = r.u32("height");
    v.width = r.u32("width");
    v.encoding = r.string("encoding");
    v.is_bigendian = r.u8("is_bigendian") != 0;
    v.step = r.u32("step");
    v.data = r.bytes("data");
  }
  if (!r.ok()) return read_failure(type, r);
  if (auto e = wire::stamp_problem(ros_type_name(type), v.header)) return *e;
  if (std::uint64_t{v.step} * v.height != v.data.size()) {
    return malformed(type, "step × height (" + dims(v.step, v.height) + ") is not the " +
                               std::to_string(v.data.size()) + " bytes of data it carries");
  }
  const PixelFormat format = pixel_format_of(v.encoding);
  if (format != PixelFormat::unknown &&
      std::uint64_t{v.width} * bytes_per_pixel(format) > v.step) {
    return malformed(type, "a row of " + std::to_string(v.width) + " " + std::string(v.encoding) +
                               " pixels does not fit its step of " + std::to_string(v.step) +
                               " bytes");
  }
  return v;
}

Expected<CompressedImageView> decode_compressed_image(std::span<const std::byte> message) {
  constexpr auto type = MessageType::compressed_image;
  cdr::Reader r(message);
  CompressedImageView v;
  if (r.encapsulation()) {
    v.header = read_header(r);
    v.format = r.string("format");
    v.data = r.bytes("data");
  }
  if (!r.ok()) return read_failure(type, r);
  if (auto e = wire::stamp_problem(ros_type_name(type), v.header)) return *e;
  return v;
}

Expected<PointCloud2View> decode_point_cloud2(std::span<const std::byte> message) {
  constexpr auto type = MessageType::point_cloud2;
  cdr::Reader r(message);
  PointCloud2View v;
  if (r.encapsulation()) {
    v.header = read_header(r);
    v.height = r.u32("height");
    v.width = r.u32("width");
    const std::uint32_t count = r.u32("fields");
    if (r.ok() && count > max_point_fields) {
      return malformed(type, "it declares " + std::to_string(count) + " point fields; at most " +
                                 std::to_string(max_point_fields) + " are accepted");
    }
    for (std::uint32_t i = 0; i < count && r.ok(); ++i) {
      PointField& f = v.field_storage[i];
      f.name = r.string("fields.name");
      f.offset = r.u32("fields.offset");
      f.datatype = r.u8("fields.datatype");
      f.count = r.u32("fields.count");
    }
    v.field_count = r.ok() ? count : 0;
    v.is_bigendian = r.boolean("is_bigendian");
    v.point_step = r.u32("point_step");
    v.row_step = r.u32("row_step");
    v.data = r.bytes("data");
    v.is_dense = r.boolean("is_dense");
  }
  if (!r.ok()) return read_failure(type, r);
  if (auto e = wire::stamp_problem(ros_type_name(type), v.header)) return *e;
  if (std::uint64_t{v.row_step} * v.height != v.data.size()) {
    return malformed(type, "row_step × height (" + dims(v.row_step, v.height) + ") is not the " +
                               std::to_string(v.data.size()) + " bytes of data it carries");
  }
  if (std::uint64_t{v.point_step} * v.width > v.row_step) {
    return malformed(type, "a row of " + std::to_string(v.width) + " points of " +
                               std::to_string(v.point_step) + " bytes does not fit its row_step of " +
                               std::to_string(v.row_step) + " bytes");
  }
  if (v.point_step == 0 && v.point_count() != 0) {
    return malformed(type, "its point_step is 0 but it claims " + std::to_string(v.point_count()) +
                               " points");
  }
  for (const PointField& f : v.fields()) {
    const std::uint32_t size = size_of(static_cast<PointFieldType>(f.datatype));
    if (size == 0) {
      return malformed(type, "field '" + std::string(f.name) + "' has the unknown datatype " +
                                 std::to_string(f.datatype));
    }
    if (std::uint64_t{f.offset} + std::uint64_t{size} * f.count > v.point_step) {
      return malformed(type, "field '" + std::string(f.name) + "' lies outside the point_step of " +
                                 std::to_string(v.point_step) + " bytes");
    }
  }
  return v;
}

Expected<ImageLayout> sim_image_layout(const ImageView& image) {
  const PixelFormat format = pixel_format_of(image.encoding);
  if (format == PixelFormat::unknown) {
    return Error{ErrorCode::invalid_argument,
                 "image encoding '" + std::string(image.encoding) +
                     "' has no SIM pixel format; publish mono8, mono16, bgr8, rgb8, bgra8, rgba8, "
                     "yuv422, yuv422_yuy2 or bayer_*8"};
  }
  if (image.is_bigendian && bytes_per_pixel(format) / ImageLayout::packed(1, 1, format).channels > 1) {
    return Error{ErrorCode::invalid_argument,
                 "big-endian " + std::string(image.encoding) +
                     " images are not supported; publish is_bigendian 0"};
  }
  if ((format == PixelFormat::uyvy || format == PixelFormat::yuyv) && image.width % 2 != 0) {
    // A 4:2:2 macropixel covers two pixels: an odd row ends in half of one (review L6).
    return Error{ErrorCode::invalid_argument,
                 "a " + std::string(image.encoding) + " image of odd width " +
                     std::to_string(image.width) + " ends in half a 4:2:2 pixel pair; publish an "
                     "even width"};
  }
  ImageLayout layout = ImageLayout::packed(image.width, image.height, format);
  layout.stride = image.step;
  const std::string why = Layout::of(layout).check(image.data.size());
  if (!why.empty()) return Error{ErrorCode::invalid_argument, "the image cannot be a SIM frame: " + why};
  return layout;
}

namespace {

bool same_fields(std::span<const PointField> a, std::span<const PointField> b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].name != b[i].name || a[i].offset != b[i].offset || a[i].datatype != b[i].datatype ||
        a[i].count != b[i].count) {
      return false;
    }
  }
  return true;
}

const PointField* find_field(const PointCloud2View& cloud, std::initializer_list<std::string_view> names) {
  for (std::string_view name : names) {
    for (const PointField& f : cloud.fields()) {
      if (f.name == name && f.count >= 1) return &f;
    }
  }
  return nullptr;
}

// One field's value of one point as a double; the field lies inside point_step (checked).
double value_at(const std::byte* point, const PointField& f) {
  const std::byte* p = point + f.offset;
  switch (static_cast<PointFieldType>(f.datatype)) {
    case PointFieldType::int8: { std::int8_t v; std::memcpy(&v, p, 1); return v; }
    case PointFieldType::uint8: { std::uint8_t v; std::memcpy(&v, p, 1); return v; }
    case PointFieldType::int16: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
    case PointFieldType::uint16: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
    case PointFieldType::int32: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
    case PointFieldType::uint32: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
    case PointFieldType::float32: { float v; std::memcpy(&v, p, 4); return v; }
    case PointFieldType::float64: { double v; std::memcpy(&v, p, 8); return v; }
  }
  return 0;
}

template <typename T>
T clamp_to(double v) {
  if (!(v > 0)) return 0;  // also NaN
  if (v >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
  return static_cast<T>(v);
}

}  // namespace

Expected<PointLayout> sim_point_layout(const PointCloud2View& cloud) {
  if (cloud.is_bigendian) {
    return Error{ErrorCode::invalid_argument,
                 "big-endian point clouds are not supported; publish is_bigendian false"};
  }
  for (PointType t : {PointType::lidar_point, PointType::xyzi32, PointType::xyz32}) {
    if (cloud.point_step == point_size(t) && same_fields(cloud.fields(), point_fields(t)) &&
        std::uint64_t{cloud.row_step} == std::uint64_t{cloud.width} * cloud.point_step) {
      return PointLayout::of(t, cloud.point_count());
    }
  }
  return Error{ErrorCode::invalid_argument,
               "the cloud's fields are not exactly a SIM point type (xyz32, xyzi32 or lidar_point); "
               "repack its points"};
}

std::string repack_problem(const PointCloud2View& cloud) {
  if (cloud.is_bigendian) return "big-endian point clouds are not supported; publish is_bigendian false";
  if (find_field(cloud, {"x"}) == nullptr || find_field(cloud, {"y"}) == nullptr ||
      find_field(cloud, {"z"}) == nullptr) {
    return "the cloud has no x, y and z fields, so it cannot become SIM points";
  }
  return {};
}

Expected<std::uint64_t> repack_points(const PointCloud2View& cloud, PointType type,
                                      std::span<std::byte> out) {
  if (std::string why = repack_problem(cloud); !why.empty()) {
    return Error{ErrorCode::invalid_argument, std::move(why)};
  }
  const std::uint32_t out_size = point_size(type);
  if (out_size == 0) return Error{ErrorCode::invalid_argument, "the target point type is unknown"};
  const PointField* x = find_field(cloud, {"x"});
  const PointField* y = find_field(cloud, {"y"});
  const PointField* z = find_field(cloud, {"z"});
  const PointField* intensity = find_field(cloud, {"intensity", "i"});
  const PointField* ring = find_field(cloud, {"ring", "channel"});
  const PointField* ret = find_field(cloud, {"return_type"});
  const PointField* time = find_field(cloud, {"time_stamp", "t"});

  const std::uint64_t n = std::min<std::uint64_t>(cloud.point_count(), out.size() / out_size);
  std::uint64_t written = 0;
  for (std::uint32_t row = 0; row < cloud.height && written < n; ++row) {
    const std::byte* row_start = cloud.data.data() + std::uint64_t{row} * cloud.row_step;
    for (std::uint32_t col = 0; col < cloud.width && written < n; ++col, ++written) {
      const std::byte* src = row_start + std::uint64_t{col} * cloud.point_step;
      LidarPoint p{};
      p.x = static_cast<float>(value_at(src, *x));
      p.y = static_cast<float>(value_at(src, *y));
      p.z = static_cast<float>(value_at(src, *z));
      if (intensity != nullptr) p.intensity = static_cast<float>(value_at(src, *intensity));
      if (time != nullptr) p.time_offset_ns = clamp_to<std::uint32_t>(value_at(src, *time));
      if (ring != nullptr) p.ring = clamp_to<std::uint16_t>(value_at(src, *ring));
      if (ret != nullptr) p.return_index = clamp_to<std::uint8_t>(value_at(src, *ret));
      // xyz32 and xyzi32 are prefixes of LidarPoint, so one copy of the leading bytes serves all.
      std::memcpy(out.data() + written * out_size, &p, out_size);
    }
  }
  return written;
}

}  // namespace sim::ros2
