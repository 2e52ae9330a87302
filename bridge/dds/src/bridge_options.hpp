// SPDX-License-Identifier: Apache-2.0
// sim_dds_bridge's command line (and YAML config) turned into per-topic options: the per-stream
// settings are "/stream=value" items (--frame-id /lidar_top=lidar_top), which is also what a YAML
// map {/lidar_top: lidar_top} becomes through apps/common's config reader.
#pragma once

#include <string>
#include <vector>

#include "inbound.hpp"
#include "outbound.hpp"
#include "sim/result.hpp"

namespace sim::bridge {

struct RawOptions {
  std::vector<std::string> publish;
  std::vector<std::string> subscribe;
  std::vector<std::string> as;         // "/local" (for the --subscribe before it) or "/remote=/local"
  std::vector<std::size_t> as_after;   // for each plain --as: how many --subscribe preceded it
  std::vector<std::string> frame_id;   // "/stream=id"
  std::vector<std::string> max_rate;   // "/stream=HZ"
  std::vector<std::string> compress;   // "/stream=jpeg[:quality]"
  bool reliable = false;            // --reliable: the published topics' writers
  bool reliable_subscribe = false;  // --reliable-subscribe: the subscribed topics' readers
};

struct BridgePlan {
  std::vector<OutboundOptions> outbound;
  std::vector<InboundOptions> inbound;
};

// The topics to bridge, or one sentence on what is wrong with the options.
Expected<BridgePlan> plan_bridge(const RawOptions& raw);

}  // namespace sim::bridge
