// SPDX-License-Identifier: Apache-2.0
// What every family's replay shares (below the families, above the loop): the end of a replay.
#pragma once

#include <string>

#include "replay_loop.hpp"

namespace sim::pcap {

// The end every family shares: the summary line, and the exit code with its one sentence.
int finish_replay(const apps::CommandLine& cli, const ReplayArgs& args, const ReplayResult& result,
                  const ReplayTarget& target, const std::string& decoded_as,
                  const apps::StopSignal& stop);

}  // namespace sim::pcap
