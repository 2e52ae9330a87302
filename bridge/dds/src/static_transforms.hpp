// SPDX-License-Identifier: Apache-2.0
// /tf_static as tf2's StaticTransformBroadcaster keeps it: one TFMessage holding every mounting
// the bridge knows (RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 1, so a node started later still gets
// it), republished whole when one changes. Each published stream contributes its sensor's
// mounting (SensorInfo: parent_frame → frame_id); the Outbounds call set() when they notice a
// new sensor description (FrameInfo::sensor_generation).
#pragma once

#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "counters.hpp"
#include "dds_session.hpp"
#include "ros_message_type.hpp"
#include "sim/sensor_info.hpp"

namespace sim::bridge {

inline constexpr const char* tf_static_topic = "/tf_static";

class StaticTransforms {
 public:
  explicit StaticTransforms(DdsSession& session) : session_(session) {}
  ~StaticTransforms();
  StaticTransforms(const StaticTransforms&) = delete;
  StaticTransforms& operator=(const StaticTransforms&) = delete;

  // The mounting of `stream`'s sensor (none: the stream's entry is removed); republishes
  // /tf_static when the list changed.
  void set(const std::string& stream, const std::optional<SensorInfo>& sensor);
  Counters& counters() noexcept { return counters_; }

 private:
  struct Entry {
    std::string parent;
    std::string child;
    Mounting mounting;
  };
  void publish();  // under mutex_

  DdsSession& session_;
  Counters counters_;
  std::mutex mutex_;
  std::map<std::string, Entry> entries_;  // by stream
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
};

}  // namespace sim::bridge

namespace sim::bridge {

// The other direction: /tf_static as other ROS 2 nodes announce it (reliable, transient local,
// so mountings published before the bridge started arrive too), for the descriptions of the
// --subscribe streams. Messages of the bridge's own /tf_static writer are not taken.
class RemoteTransforms final : private MessageSink {
 public:
  explicit RemoteTransforms(DdsSession& session);
  ~RemoteTransforms();
  RemoteTransforms(const RemoteTransforms&) = delete;
  RemoteTransforms& operator=(const RemoteTransforms&) = delete;

  struct Parent {
    std::string frame;
    Mounting mounting;
  };
  // The newest mounting of the frame `child` announced so far, if any (takes what arrived).
  std::optional<Parent> mounting_of(const std::string& child);
  Counters& counters() noexcept { return counters_; }

 private:
  void deliver(std::span<const std::byte> message) override;

  DdsSession& session_;
  Counters counters_;
  std::mutex mutex_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::map<std::string, Parent> known_;  // by child frame
};

}  // namespace sim::bridge
