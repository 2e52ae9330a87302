// SPDX-License-Identifier: Apache-2.0
#include "foxglove_messages.hpp"

#include <algorithm>
#include <array>

#include "sim/ros2/message.hpp"

namespace sim::foxglove {
namespace {

#define SIM_FOXGLOVE_SEPARATOR \
  "================================================================================\n"
#define SIM_FOXGLOVE_TIME       \
  SIM_FOXGLOVE_SEPARATOR        \
  "MSG: builtin_interfaces/msg/Time\n" \
  "int32 sec\n"                 \
  "uint32 nanosec\n"

constexpr std::string_view kCalibrationSchema =
    "builtin_interfaces/Time timestamp\n"
    "string frame_id\n"
    "uint32 width\n"
    "uint32 height\n"
    "string distortion_model\n"
    "float64[] d\n"
    "float64[9] k\n"
    "float64[9] r\n"
    "float64[12] p\n" SIM_FOXGLOVE_TIME;

constexpr std::string_view kTransformsSchema =
    "foxglove_msgs/msg/FrameTransform[] transforms\n" SIM_FOXGLOVE_SEPARATOR
    "MSG: foxglove_msgs/msg/FrameTransform\n"
    "builtin_interfaces/Time timestamp\n"
    "string parent_frame_id\n"
    "string child_frame_id\n"
    "geometry_msgs/msg/Vector3 translation\n"
    "geometry_msgs/msg/Quaternion rotation\n" SIM_FOXGLOVE_SEPARATOR
    "MSG: geometry_msgs/msg/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n" SIM_FOXGLOVE_SEPARATOR
    "MSG: geometry_msgs/msg/Quaternion\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n"
    "float64 w\n" SIM_FOXGLOVE_TIME;

// XCDR1 little endian into a growing buffer; alignment counts from after the 4-byte
// encapsulation header, as in every CDR message of the project (sim::ros2).
class CdrOut {
 public:
  CdrOut() { bytes_ = {std::byte{0x00}, std::byte{0x01}, std::byte{0x00}, std::byte{0x00}}; }
  void u32(std::uint32_t v) { put(v); }
  void i32(std::int32_t v) { put(v); }
  void f64(double v) { put(v); }
  void string(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    raw(s.data(), s.size());
    const char nul = 0;
    raw(&nul, 1);
  }
  void time(std::int64_t ns) {
    const ros2::Time t = ros2::Time::from_ns(ns);
    i32(t.sec);
    u32(t.nanosec);
  }
  template <std::size_t N>
  void f64_array(const std::array<double, N>& values) {
    for (const double v : values) f64(v);
  }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  template <typename T>
  void put(T v) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(std::byte{0});
    raw(&v, sizeof v);  // this host is little endian, as every platform SIM builds for
  }
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::byte*>(p);
    bytes_.insert(bytes_.end(), b, b + n);
  }
  std::vector<std::byte> bytes_;
};

}  // namespace

std::string_view calibration_schema() noexcept { return kCalibrationSchema; }
std::string_view transforms_schema() noexcept { return kTransformsSchema; }

std::string image_topic(std::string_view stream, bool compressed) {
  return std::string(stream) + (compressed ? "/compressed" : "/image_raw");
}

std::string frame_of(std::string_view stream, const std::optional<SensorInfo>& sensor) {
  if (sensor && !sensor->frame_id.empty()) return sensor->frame_id;
  if (!stream.empty() && stream.front() == '/') stream.remove_prefix(1);
  return std::string(stream);
}

std::string calibration_topic(std::string_view stream) {
  return std::string(stream) + "/camera_info";
}

CameraCalibration reduced_calibration(const CameraCalibration& calibration) {
  CameraCalibration c = calibration;
  const double bx = std::max(1u, c.binning_x), by = std::max(1u, c.binning_y);
  const double x0 = c.roi.x_offset, y0 = c.roi.y_offset;
  // Row 0 of K and P maps to u, row 1 to v: u' = (u - x_offset) / bx, v' = (v - y_offset) / by.
  const auto reduce_rows = [&](double* row0, double* row1, double* row2, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      row0[i] = (row0[i] - x0 * row2[i]) / bx;
      row1[i] = (row1[i] - y0 * row2[i]) / by;
    }
  };
  reduce_rows(&c.k[0], &c.k[3], &c.k[6], 3);
  reduce_rows(&c.p[0], &c.p[4], &c.p[8], 4);
  const std::uint32_t full_w = c.roi.width > 0 ? c.roi.width : c.width;
  const std::uint32_t full_h = c.roi.height > 0 ? c.roi.height : c.height;
  c.width = static_cast<std::uint32_t>(full_w / std::max(1u, c.binning_x));
  c.height = static_cast<std::uint32_t>(full_h / std::max(1u, c.binning_y));
  c.binning_x = c.binning_y = 0;
  c.roi = {};
  return c;
}

std::vector<std::byte> encode_calibration(const CameraCalibration& full,
                                          std::string_view frame_id, std::int64_t stamp_ns) {
  const CameraCalibration calibration = reduced_calibration(full);
  std::array<double, 12> p = calibration.p;
  if (p[0] == 0 && p[5] == 0) {
    p = {calibration.k[0], calibration.k[1], calibration.k[2], 0,
         calibration.k[3], calibration.k[4], calibration.k[5], 0,
         calibration.k[6], calibration.k[7], calibration.k[8], 0};
  }
  CdrOut out;
  out.time(stamp_ns);
  out.string(frame_id);
  out.u32(calibration.width);
  out.u32(calibration.height);
  out.string(calibration.distortion_model == "equidistant" ? "kannala_brandt"
                                                           : calibration.distortion_model);
  out.u32(static_cast<std::uint32_t>(calibration.d.size()));
  for (const double v : calibration.d) out.f64(v);
  out.f64_array(calibration.k);
  out.f64_array(calibration.r);
  out.f64_array(p);
  return out.take();
}

std::vector<std::byte> encode_transforms(const std::vector<FrameTransform>& transforms,
                                         std::int64_t stamp_ns) {
  CdrOut out;
  out.u32(static_cast<std::uint32_t>(transforms.size()));
  for (const FrameTransform& t : transforms) {
    out.time(stamp_ns);
    out.string(t.parent);
    out.string(t.child);
    for (const double v : t.mounting.translation) out.f64(v);
    for (const double v : t.mounting.rotation) out.f64(v);
  }
  return out.take();
}

}  // namespace sim::foxglove
