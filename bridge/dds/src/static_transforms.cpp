// SPDX-License-Identifier: Apache-2.0
#include "static_transforms.hpp"

#include <vector>

#include "ros_message_type.hpp"
#include "sim/clock.hpp"
#include "sim/ros2/metadata.hpp"

namespace sim::bridge {

StaticTransforms::~StaticTransforms() { session_.delete_writer(writer_); }

void StaticTransforms::set(const std::string& stream, const std::optional<SensorInfo>& sensor) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(stream);
  if (!sensor || !sensor->mounting) {
    if (it == entries_.end()) return;
    entries_.erase(it);
  } else {
    Entry entry{sensor->parent_frame, sensor->frame_id, *sensor->mounting};
    if (it != entries_.end() && it->second.parent == entry.parent &&
        it->second.child == entry.child && it->second.mounting == entry.mounting) {
      return;
    }
    entries_[stream] = std::move(entry);
  }
  publish();
}

void StaticTransforms::publish() {
  if (writer_ == nullptr) {
    std::string error;
    writer_ = session_.create_writer(ros2::dds_topic_name(tf_static_topic),
                                     ros2::tf_message_dds_type_name,
                                     QosChoice{.reliable = true, .depth = 1, .transient_local = true},
                                     error);
    if (writer_ == nullptr) {
      counters_.problem(error);
      return;
    }
    counters_.connected.store(true);
  }
  const ros2::Time stamp = ros2::Time::from_ns(realtime_ns());
  std::vector<ros2::TransformStamped> transforms;
  for (const auto& [stream, e] : entries_) {
    transforms.push_back({ros2::Header{stamp, e.parent}, e.child, e.mounting});
  }
  auto bytes = ros2::encode_tf_message(transforms);
  if (!bytes) {
    counters_.count(counters_.failed);
    counters_.problem("/tf_static: " + bytes.error().message);
    return;
  }
  SerializedMessage message{*bytes};
  if (writer_->write(&message)) {
    counters_.count(counters_.bridged);
  } else {
    counters_.count(counters_.failed);
  }
}

}  // namespace sim::bridge

namespace sim::bridge {

RemoteTransforms::RemoteTransforms(DdsSession& session) : session_(session) {
  std::string error;
  // tf2's listener QoS: depth 100, so every broadcaster's latest message is kept.
  reader_ = session_.create_reader(ros2::dds_topic_name(tf_static_topic), ros2::tf_message_dds_type_name,
                                   QosChoice{.reliable = true, .depth = 100, .transient_local = true},
                                   error);
  if (reader_ == nullptr) counters_.problem(error);
}

RemoteTransforms::~RemoteTransforms() { session_.delete_reader(reader_); }

std::optional<RemoteTransforms::Parent> RemoteTransforms::mounting_of(const std::string& child) {
  std::lock_guard lock(mutex_);
  if (reader_ != nullptr) {
    IncomingMessage sample{this};
    IncomingMessage ignored{nullptr};
    eprosima::fastdds::dds::SampleInfo info;
    while (reader_->get_first_untaken_info(&info) == ReturnCode_t::RETCODE_OK) {
      if (reader_->take_next_sample(session_.own_sample(info) ? &ignored : &sample, &info) !=
          ReturnCode_t::RETCODE_OK) {
        break;
      }
    }
  }
  auto it = known_.find(child);
  if (it == known_.end()) return std::nullopt;
  return it->second;
}

void RemoteTransforms::deliver(std::span<const std::byte> message) {
  counters_.count(counters_.frames_seen);
  auto transforms = ros2::decode_tf_message(message);
  if (!transforms) {
    counters_.count(counters_.malformed);
    counters_.problem("/tf_static: " + transforms.error().message);
    return;
  }
  for (const ros2::TransformStamped& t : *transforms) {
    known_[std::string(t.child_frame_id)] = Parent{std::string(t.header.frame_id), t.transform};
  }
  counters_.count(counters_.bridged);
}

}  // namespace sim::bridge
