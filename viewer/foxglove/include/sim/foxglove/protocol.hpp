// SPDX-License-Identifier: Apache-2.0
// The Foxglove WebSocket protocol (foxglove.websocket.v1) as plain values: the JSON a client
// sends, parsed into requests; the JSON and binary headers the server sends, built from values.
// No sockets here, so the parser of outside bytes is fuzzed on its own (tests/viewer/foxglove).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace sim::foxglove {

// The subprotocol names of the Foxglove WebSocket protocol: Foxglove's current apps and SDK
// servers speak foxglove.sdk.v1, older ones and Lichtblick foxglove.websocket.v1; the protocol
// is the same. The server answers with the one the client offered.
inline constexpr std::string_view kSubprotocols[] = {"foxglove.sdk.v1", "foxglove.websocket.v1"};

// One advertised channel: a SIM stream as Foxglove sees it.
struct Channel {
  std::uint32_t id = 0;
  std::string topic;            // the stream name, "/lidar_top"
  std::string encoding;         // "cdr"
  std::string schema_name;      // "sensor_msgs/msg/PointCloud2"
  std::string schema_encoding;  // "ros2msg"
  std::string schema;           // the message definition text
  friend bool operator==(const Channel&, const Channel&) = default;
};

struct Subscription {
  std::uint32_t id = 0;          // chosen by the client
  std::uint32_t channel_id = 0;
};
struct SubscribeRequest {
  std::vector<Subscription> subscriptions;
};
struct UnsubscribeRequest {
  std::vector<std::uint32_t> subscription_ids;
};
// A message the server does not act on; `message` is the one sentence sent back as a status.
struct RejectedRequest {
  std::string message;
};
using ClientRequest = std::variant<SubscribeRequest, UnsubscribeRequest, RejectedRequest>;

// More ids than this in one request are refused: no client needs them, and a flood must not
// make the server allocate without bound.
inline constexpr std::size_t kMaxIdsPerRequest = 1024;

// Parses one text frame from a client. Never throws; anything but a well-formed subscribe or
// unsubscribe becomes a RejectedRequest saying why.
ClientRequest parse_client_request(std::string_view text);

enum class StatusLevel : int { info = 0, warning = 1, error = 2 };

std::string server_info_json(std::string_view name, std::string_view session_id);
std::string advertise_json(std::span<const Channel> channels);
std::string unadvertise_json(std::span<const std::uint32_t> channel_ids);
std::string status_json(StatusLevel level, std::string_view message);

// Server binary opcode 0x01 "message data": opcode, uint32 subscription id, uint64 timestamp
// (ns), all little-endian; the message payload follows in the same WebSocket frame.
inline constexpr std::size_t kMessageHeaderSize = 13;
std::array<std::byte, kMessageHeaderSize> message_header(std::uint32_t subscription_id,
                                                         std::uint64_t timestamp_ns) noexcept;

}  // namespace sim::foxglove
