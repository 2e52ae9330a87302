// SPDX-License-Identifier: Apache-2.0
#include "ros_message_type.hpp"

#include <cstring>
#include <string>

namespace sim::bridge {

using eprosima::fastrtps::rtps::SerializedPayload_t;

RosMessageType::RosMessageType(ros2::MessageType type) : type_(type) {
  setName(std::string(ros2::dds_type_name(type)).c_str());
  // Only a first guess for payload buffers: the writers and readers use reallocating memory
  // policies, so a 7 MB image gets a 7 MB payload.
  m_typeSize = 64 * 1024;
  m_isGetKeyDefined = false;
}

bool RosMessageType::serialize(void* data, SerializedPayload_t* payload) {
  auto& message = *static_cast<OutgoingMessage*>(data);
  const std::size_t size = message.plan->size();
  if (payload->max_size < size) return false;
  if (message.plan->write(message.payload, {reinterpret_cast<std::byte*>(payload->data), size}) != size) {
    return false;
  }
  payload->length = static_cast<std::uint32_t>(size);
  payload->encapsulation = CDR_LE;
  // The seqlock rule: the copy counts only if the SIM writer did not start overwriting the slot
  // while it was made. A torn frame is never sent.
  if (message.borrow != nullptr && !message.borrow->still_valid()) {
    message.torn = true;
    return false;
  }
  return true;
}

bool RosMessageType::deserialize(SerializedPayload_t* payload, void* data) {
  auto& message = *static_cast<IncomingMessage*>(data);
  if (message.sink != nullptr) {
    message.sink->deliver({reinterpret_cast<const std::byte*>(payload->data), payload->length});
  }
  return true;
}

std::function<std::uint32_t()> RosMessageType::getSerializedSizeProvider(void* data) {
  const auto size = static_cast<std::uint32_t>(static_cast<OutgoingMessage*>(data)->plan->size());
  return [size] { return size; };
}

void* RosMessageType::createData() { return new IncomingMessage; }
void RosMessageType::deleteData(void* data) { delete static_cast<IncomingMessage*>(data); }

SerializedMessageType::SerializedMessageType(std::string_view dds_type_name) {
  setName(std::string(dds_type_name).c_str());
  m_typeSize = 4 * 1024;
  m_isGetKeyDefined = false;
}

bool SerializedMessageType::serialize(void* data, SerializedPayload_t* payload) {
  const auto& message = *static_cast<SerializedMessage*>(data);
  if (message.bytes.size() < 4 || payload->max_size < message.bytes.size()) return false;
  std::memcpy(payload->data, message.bytes.data(), message.bytes.size());
  payload->length = static_cast<std::uint32_t>(message.bytes.size());
  payload->encapsulation = CDR_LE;
  return true;
}

bool SerializedMessageType::deserialize(SerializedPayload_t* payload, void* data) {
  auto& message = *static_cast<IncomingMessage*>(data);
  if (message.sink != nullptr) {
    message.sink->deliver({reinterpret_cast<const std::byte*>(payload->data), payload->length});
  }
  return true;
}

std::function<std::uint32_t()> SerializedMessageType::getSerializedSizeProvider(void* data) {
  const auto size = static_cast<std::uint32_t>(static_cast<SerializedMessage*>(data)->bytes.size());
  return [size] { return size; };
}

void* SerializedMessageType::createData() { return new IncomingMessage; }
void SerializedMessageType::deleteData(void* data) { delete static_cast<IncomingMessage*>(data); }

}  // namespace sim::bridge
