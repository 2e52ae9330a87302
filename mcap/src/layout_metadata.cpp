// SPDX-License-Identifier: Apache-2.0
#include "sim/mcap/layout_metadata.hpp"

#include <charconv>

namespace sim::mcap {

namespace {

std::optional<std::uint64_t> number(const Metadata& m, const std::string& key) {
  const auto it = m.find(key);
  if (it == m.end()) return std::nullopt;
  std::uint64_t value = 0;
  const auto& s = it->second;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  return value;
}

std::optional<std::uint32_t> number32(const Metadata& m, const std::string& key) {
  const auto v = number(m, key);
  if (!v || *v > UINT32_MAX) return std::nullopt;
  return static_cast<std::uint32_t>(*v);
}

}  // namespace

const std::string& sensor_data_qos_yaml() {
  // rmw_qos_profile_sensor_data: history KEEP_LAST (1), depth 5, reliability BEST_EFFORT (2),
  // durability VOLATILE (2); zero durations mean "default".
  static const std::string yaml =
      "- history: 1\n"
      "  depth: 5\n"
      "  reliability: 2\n"
      "  durability: 2\n"
      "  deadline:\n    sec: 0\n    nsec: 0\n"
      "  lifespan:\n    sec: 0\n    nsec: 0\n"
      "  liveliness: 1\n"
      "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
      "  avoid_ros_namespace_conventions: false\n";
  return yaml;
}

Metadata stream_metadata(const std::string& stream, const Layout& layout, std::uint64_t capacity) {
  Metadata m;
  m["offered_qos_profiles"] = sensor_data_qos_yaml();
  m["sim.stream"] = stream;
  m["sim.layout"] = layout.describe();
  m["sim.capacity"] = std::to_string(capacity);
  switch (layout.kind) {
    case LayoutKind::bytes: m["sim.kind"] = "bytes"; break;
    case LayoutKind::image:
      m["sim.kind"] = "image";
      m["sim.image.width"] = std::to_string(layout.image.width);
      m["sim.image.height"] = std::to_string(layout.image.height);
      m["sim.image.channels"] = std::to_string(layout.image.channels);
      m["sim.image.stride"] = std::to_string(layout.image.stride);
      m["sim.image.format"] = std::to_string(static_cast<std::uint32_t>(layout.image.format));
      m["sim.image.bit_depth"] = std::to_string(layout.image.bit_depth);
      break;
    case LayoutKind::points:
      m["sim.kind"] = "points";
      m["sim.points.type"] = std::to_string(static_cast<std::uint32_t>(layout.points.type));
      m["sim.points.point_size"] = std::to_string(layout.points.point_size);
      m["sim.points.max_points"] = std::to_string(layout.points.max_points);
      break;
  }
  return m;
}

std::optional<StreamShape> stream_shape(const Metadata& m) {
  const auto kind = m.find("sim.kind");
  const auto capacity = number(m, "sim.capacity");
  if (kind == m.end() || !capacity) return std::nullopt;
  StreamShape shape;
  shape.capacity = *capacity;
  if (kind->second == "bytes") {
    shape.layout = Layout::raw();
  } else if (kind->second == "image") {
    const auto w = number32(m, "sim.image.width"), h = number32(m, "sim.image.height"),
               c = number32(m, "sim.image.channels"), s = number32(m, "sim.image.stride"),
               f = number32(m, "sim.image.format"), d = number32(m, "sim.image.bit_depth");
    if (!w || !h || !c || !s || !f || !d) return std::nullopt;
    ImageLayout image{*w, *h, *c, *s, static_cast<PixelFormat>(*f), *d};
    shape.layout = Layout::of(image);
  } else if (kind->second == "points") {
    const auto t = number32(m, "sim.points.type"), s = number32(m, "sim.points.point_size");
    const auto n = number(m, "sim.points.max_points");
    if (!t || !s || !n) return std::nullopt;
    shape.layout = Layout::of(PointLayout{static_cast<PointType>(*t), *s, *n});
  } else {
    return std::nullopt;
  }
  if (!shape.layout.check(shape.capacity).empty()) return std::nullopt;
  return shape;
}

}  // namespace sim::mcap
