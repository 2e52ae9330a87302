// SPDX-License-Identifier: Apache-2.0
// rmw_dds_common/msg/ParticipantEntitiesInfo: what a participant sends on the DDS topic
// ros_discovery_info (RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 1) so ROS 2 (Iron and later) lists
// its nodes and which node owns which endpoint: `ros2 node list` and `ros2 node info`.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sim/result.hpp"

namespace sim::ros2 {

inline constexpr std::string_view graph_dds_topic = "ros_discovery_info";  // no "rt/" prefix
inline constexpr std::string_view participant_entities_info_type_name =
    "rmw_dds_common/msg/ParticipantEntitiesInfo";
inline constexpr std::string_view participant_entities_info_dds_type_name =
    "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_";

// A DDS entity's GUID: the 12-byte prefix then the 4-byte entity id (16 bytes from Iron on).
using Gid = std::array<std::uint8_t, 16>;

struct NodeEntities {
  std::string_view node_namespace;  // "/"
  std::string_view node_name;       // "sim_dds_bridge"
  std::span<const Gid> readers;
  std::span<const Gid> writers;
};

// The serialized message (XCDR1 little endian) of one participant with its nodes.
std::vector<std::byte> encode_participant_entities_info(const Gid& participant,
                                                        std::span<const NodeEntities> nodes);

// What a received ParticipantEntitiesInfo says: the participant, its nodes ("/ns/name" as
// ROS names them), and every reader and writer GID of all its nodes.
struct ParticipantEntities {
  Gid participant{};
  std::vector<std::string> nodes;
  std::vector<Gid> readers;
  std::vector<Gid> writers;
};

// Most nodes one message may list here (a process with more is not a sensor pipeline).
inline constexpr std::size_t max_graph_nodes = 1024;

Expected<ParticipantEntities> decode_participant_entities_info(std::span<const std::byte> message);

}  // namespace sim::ros2
