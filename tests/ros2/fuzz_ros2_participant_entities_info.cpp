// SPDX-License-Identifier: Apache-2.0
// Fuzzes decode_participant_entities_info: every ros_discovery_info message the bridge receives.
// What it accepts must encode back to a message that decodes to the same GIDs.
#include <cstddef>
#include <cstdint>
#include <span>

#include "sim/ros2/graph.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto info = sim::ros2::decode_participant_entities_info(std::as_bytes(std::span(data, size)));
  if (!info) return 0;
  const sim::ros2::NodeEntities node{"/", "all", info->readers, info->writers};
  const auto again = sim::ros2::encode_participant_entities_info(info->participant, {&node, 1});
  auto back = sim::ros2::decode_participant_entities_info(again);
  if (!back || back->participant != info->participant || back->readers != info->readers ||
      back->writers != info->writers) {
    __builtin_trap();
  }
  return 0;
}
