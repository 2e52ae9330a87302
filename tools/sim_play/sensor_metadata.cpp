// SPDX-License-Identifier: Apache-2.0
#include "sensor_metadata.hpp"

#include <array>
#include <cmath>

#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/metadata.hpp"

namespace sim::play {

namespace {

// "sensor_msgs/msg/CameraInfo" (ROS 2) or "sensor_msgs/CameraInfo" (older writers).
bool is_type(const mcap::Schema* schema, std::string_view ros2_name) {
  if (schema == nullptr) return false;
  std::string shortened(ros2_name);
  shortened.erase(shortened.find("/msg/"), 4);
  return schema->name == ros2_name || schema->name == shortened;
}

// The image topic without the image_transport suffix of a compressed one.
std::string_view image_base(std::string_view topic) {
  constexpr std::string_view suffix = "/compressed";
  if (topic.size() > suffix.size() && topic.substr(topic.size() - suffix.size()) == suffix) {
    topic.remove_suffix(suffix.size());
  }
  return topic;
}

using Quaternion = std::array<double, 4>;  // x, y, z, w

Quaternion unit(const Quaternion& q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 0.0)) return q;  // left for sensor_info_problem to refuse
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

// a * b (Hamilton product, x y z w).
Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
          a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
          a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
          a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
}

// `v` turned by the unit quaternion `q`.
std::array<double, 3> rotate(const Quaternion& q, const std::array<double, 3>& v) {
  const Quaternion p = multiply(multiply(q, {v[0], v[1], v[2], 0.0}), {-q[0], -q[1], -q[2], q[3]});
  return {p[0], p[1], p[2]};
}

// The mounting of c in a from b in a (`outer`) and c in b (`inner`), as tf2 chains transforms.
Mounting compose(const Mounting& outer, const Mounting& inner) {
  const Quaternion q = unit(outer.rotation);
  const std::array<double, 3> moved = rotate(q, inner.translation);
  Mounting m;
  for (std::size_t i = 0; i < 3; ++i) m.translation[i] = outer.translation[i] + moved[i];
  m.rotation = unit(multiply(q, unit(inner.rotation)));
  return m;
}

// Review turn 4 M5: every child's chain of mountings composed up to base_link, or to the root of
// its tree. A loop (a bad file) ends after as many hops as there are mountings.
void compose_chains(Mountings& mountings) {
  mountings.to_root.clear();
  for (const auto& [child, direct] : mountings.by_child) {
    std::pair<std::string, Mounting> chained = direct;
    for (std::size_t hops = 0; hops < mountings.by_child.size() && chained.first != "base_link"; ++hops) {
      const auto up = mountings.by_child.find(chained.first);
      if (up == mountings.by_child.end() || up->first == child) break;
      chained = {up->second.first, compose(up->second.second, chained.second)};
    }
    mountings.to_root.emplace(child, std::move(chained));
  }
}

}  // namespace

SensorMetadata::SensorMetadata(const mcap::Reader& reader) {
  for (const auto& [id, channel] : reader.channels()) {
    if (channel.message_encoding != "cdr") continue;
    const mcap::Schema* schema = reader.schema_of(channel);
    if (is_type(schema, ros2::camera_info_type_name)) {
      kinds_[id] = Kind::camera_info;
      topics_[id] = channel.topic;
    } else if (is_type(schema, ros2::tf_message_type_name) && channel.topic == "/tf_static") {
      kinds_[id] = Kind::tf_static;
      topics_[id] = channel.topic;
    } else if (is_type(schema, ros2::diagnostic_array_type_name)) {
      kinds_[id] = Kind::diagnostics;
      topics_[id] = channel.topic;
    }
  }
}

void SensorMetadata::attach(Players& players) {
  for (auto& [id, player] : players) {
    player.use_mountings(&mountings_);
    const std::string sibling = ros2::camera_info_topic_for(image_base(player.topic()));
    for (const auto& [info_id, topic] : topics_) {
      if (kinds_[info_id] == Kind::camera_info && topic == sibling) images_of_[info_id].push_back(id);
    }
  }
}

std::optional<Error> SensorMetadata::take(std::uint16_t channel, std::span<const std::byte> message,
                                          Players& players) {
  if (kinds_.at(channel) == Kind::camera_info) {
    const auto targets = images_of_.find(channel);
    if (targets == images_of_.end()) return std::nullopt;  // no image topic of ours beside it
    auto info = ros2::decode_camera_info(message);
    if (!info) return Error{info.error().code, topics_[channel] + ": " + info.error().message};
    for (const std::uint16_t image : targets->second) players.at(image).set_calibration(info->calibration);
    return std::nullopt;
  }
  if (kinds_.at(channel) == Kind::diagnostics) return take_diagnostics(channel, message, players);
  auto transforms = ros2::decode_tf_message(message);
  if (!transforms) return Error{transforms.error().code, "/tf_static: " + transforms.error().message};
  for (const auto& t : *transforms) {
    mountings_.by_child[std::string(t.child_frame_id)] = {std::string(t.header.frame_id), t.transform};
  }
  compose_chains(mountings_);
  ++mountings_.generation;
  return std::nullopt;
}

std::optional<Error> SensorMetadata::take_diagnostics(std::uint16_t channel,
                                                      std::span<const std::byte> message,
                                                      Players& players) {
  auto array = ros2::decode_diagnostic_array(message);
  if (!array) return Error{array.error().code, topics_[channel] + ": " + array.error().message};
  for (const ros2::DiagnosticStatus& status : array->status) {
    const auto stream = ros2::stream_of_clock_diagnostic(status.name);
    // Other nodes' diagnostics, and a stream that reported no clock, carry no record.
    if (!stream || status.value("clock_source") == nullptr) continue;
    auto clock = ros2::clock_from_diagnostic(status);
    if (!clock) return Error{clock.error().code, topics_[channel] + ": " + clock.error().message};
    for (auto& [id, player] : players) {
      if (player.recorded_stream() == *stream) player.set_clock(*clock);
    }
  }
  return std::nullopt;
}

}  // namespace sim::play
