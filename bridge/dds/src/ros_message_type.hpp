// SPDX-License-Identifier: Apache-2.0
// The Fast DDS type of one ROS 2 message (sensor_msgs::msg::dds_::Image_ …), written by hand so
// that serializing is the one copy of a frame: serialize() writes the sim::ros2 prefix and the
// borrowed SIM slot straight into Fast DDS's SerializedPayload, and deserialize() hands the
// received bytes to the bridge, which decodes them straight into a loaned SIM slot.
#pragma once

#include <fastdds/dds/topic/TopicDataType.hpp>

#include <cstddef>
#include <span>
#include <string_view>

#include "sim/reader.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"

namespace sim::bridge {

// What DataWriter::write() is given.
struct OutgoingMessage {
  const ros2::MessagePlan* plan = nullptr;
  std::span<const std::byte> payload;  // the frame's bytes (in the SIM slot, or a JPEG buffer)
  const Borrow* borrow = nullptr;      // the slot the payload lies in, checked after the copy
  bool torn = false;                   // set when the SIM writer overwrote the slot meanwhile
};

// What DataWriter::write() is given for a message serialized beforehand (CameraInfo, TFMessage,
// ParticipantEntitiesInfo): its whole bytes, encapsulation header first.
struct SerializedMessage {
  std::span<const std::byte> bytes;
};

// Receives the serialized bytes of each message DataReader::take_next_sample() takes.
class MessageSink {
 public:
  virtual void deliver(std::span<const std::byte> message) = 0;

 protected:
  ~MessageSink() = default;
};

// What DataReader::take_next_sample() is given.
struct IncomingMessage {
  MessageSink* sink = nullptr;
};

class RosMessageType final : public eprosima::fastdds::dds::TopicDataType {
 public:
  explicit RosMessageType(ros2::MessageType type);

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override;
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override;
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override;
  void* createData() override;
  void deleteData(void* data) override;
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
  // Unbounded strings and sequences: not plain, so Fast DDS never tries data-sharing loans.
  bool is_bounded() const override { return false; }
  bool is_plain() const override { return false; }

  ros2::MessageType message_type() const noexcept { return type_; }

 private:
  ros2::MessageType type_;
};

// The Fast DDS type of a message this layer serializes whole beforehand (small and rare: the
// calibration, the mountings, the graph). Reading hands the bytes to the sink, as RosMessageType.
class SerializedMessageType final : public eprosima::fastdds::dds::TopicDataType {
 public:
  explicit SerializedMessageType(std::string_view dds_type_name);

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override;
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override;
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override;
  void* createData() override;
  void deleteData(void* data) override;
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
  bool is_bounded() const override { return false; }
  bool is_plain() const override { return false; }
};

}  // namespace sim::bridge
