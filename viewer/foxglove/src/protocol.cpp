// SPDX-License-Identifier: Apache-2.0
#include "sim/foxglove/protocol.hpp"

#include <nlohmann/json.hpp>

namespace sim::foxglove {
namespace {

using nlohmann::json;

// Ops the protocol defines that this server does not offer (it advertises no capability for
// them); a client sending one gets told so instead of being dropped.
bool is_unsupported_known_op(std::string_view op) {
  static constexpr std::string_view known[] = {
      "advertise",         "unadvertise",       "getParameters",
      "setParameters",     "subscribeParameterUpdates", "unsubscribeParameterUpdates",
      "subscribeConnectionGraph", "unsubscribeConnectionGraph", "fetchAsset"};
  for (const auto k : known) {
    if (op == k) return true;
  }
  return false;
}

// A protocol id: a JSON integer in uint32 range.
bool read_id(const json& value, std::uint32_t& out) {
  if (!value.is_number_integer()) return false;
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    if (v > 0xFFFF'FFFFu) return false;
    out = static_cast<std::uint32_t>(v);
    return true;
  }
  const auto v = value.get<std::int64_t>();
  if (v < 0 || v > 0xFFFF'FFFF) return false;
  out = static_cast<std::uint32_t>(v);
  return true;
}

ClientRequest parse_subscribe(const json& message) {
  const auto it = message.find("subscriptions");
  if (it == message.end() || !it->is_array()) {
    return RejectedRequest{"subscribe needs a \"subscriptions\" array of {id, channelId}."};
  }
  if (it->size() > kMaxIdsPerRequest) {
    return RejectedRequest{"subscribe lists more than " + std::to_string(kMaxIdsPerRequest) +
                           " subscriptions; send fewer at a time."};
  }
  SubscribeRequest request;
  for (const json& entry : *it) {
    Subscription s;
    if (!entry.is_object() || !entry.contains("id") || !entry.contains("channelId") ||
        !read_id(entry["id"], s.id) || !read_id(entry["channelId"], s.channel_id)) {
      return RejectedRequest{
          "each subscription needs integer \"id\" and \"channelId\" (0 to 4294967295)."};
    }
    request.subscriptions.push_back(s);
  }
  return request;
}

ClientRequest parse_unsubscribe(const json& message) {
  const auto it = message.find("subscriptionIds");
  if (it == message.end() || !it->is_array()) {
    return RejectedRequest{"unsubscribe needs a \"subscriptionIds\" array of integers."};
  }
  if (it->size() > kMaxIdsPerRequest) {
    return RejectedRequest{"unsubscribe lists more than " + std::to_string(kMaxIdsPerRequest) +
                           " ids; send fewer at a time."};
  }
  UnsubscribeRequest request;
  for (const json& entry : *it) {
    std::uint32_t id = 0;
    if (!read_id(entry, id)) {
      return RejectedRequest{"subscriptionIds must be integers from 0 to 4294967295."};
    }
    request.subscription_ids.push_back(id);
  }
  return request;
}

}  // namespace

ClientRequest parse_client_request(std::string_view text) {
  // Depth-limited by nlohmann's recursive parser only through the frame size limit the server
  // sets (a client frame is at most 64 KiB), which keeps recursion shallow enough.
  const json message = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded()) {
    return RejectedRequest{"the message is not valid JSON; send one JSON object with an \"op\"."};
  }
  if (!message.is_object() || !message.contains("op") || !message["op"].is_string()) {
    return RejectedRequest{"the message has no \"op\" string; send a JSON object with an \"op\"."};
  }
  const auto& op = message["op"].get_ref<const std::string&>();
  if (op == "subscribe") return parse_subscribe(message);
  if (op == "unsubscribe") return parse_unsubscribe(message);
  if (is_unsupported_known_op(op)) {
    return RejectedRequest{"op \"" + op +
                           "\" is not offered by this server (see serverInfo capabilities)."};
  }
  return RejectedRequest{"unknown op \"" + op.substr(0, 64) +
                         "\"; this server understands subscribe and unsubscribe."};
}

std::string server_info_json(std::string_view name, std::string_view session_id) {
  const json message = {{"op", "serverInfo"},
                        {"name", name},
                        {"capabilities", json::array()},
                        {"supportedEncodings", json::array()},
                        {"metadata", json::object()},
                        {"sessionId", session_id}};
  return message.dump();
}

std::string advertise_json(std::span<const Channel> channels) {
  json list = json::array();
  for (const Channel& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", c.schema_encoding}});
  }
  return json{{"op", "advertise"}, {"channels", std::move(list)}}.dump();
}

std::string unadvertise_json(std::span<const std::uint32_t> channel_ids) {
  return json{{"op", "unadvertise"},
              {"channelIds", std::vector<std::uint32_t>(channel_ids.begin(), channel_ids.end())}}
      .dump();
}

std::string status_json(StatusLevel level, std::string_view message) {
  // Replace invalid UTF-8 rather than throw: a status may quote what the client sent.
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::array<std::byte, kMessageHeaderSize> message_header(std::uint32_t subscription_id,
                                                         std::uint64_t timestamp_ns) noexcept {
  std::array<std::byte, kMessageHeaderSize> header{};
  header[0] = std::byte{0x01};
  for (int i = 0; i < 4; ++i) {
    header[static_cast<std::size_t>(1 + i)] = std::byte((subscription_id >> (8 * i)) & 0xFFu);
  }
  for (int i = 0; i < 8; ++i) {
    header[static_cast<std::size_t>(5 + i)] = std::byte((timestamp_ns >> (8 * i)) & 0xFFu);
  }
  return header;
}

}  // namespace sim::foxglove
