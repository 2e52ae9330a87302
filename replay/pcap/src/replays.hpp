// SPDX-License-Identifier: Apache-2.0
// The families sim_replay_pcap replays, each with its own command line on apps/common.
#pragma once

#include <string>

#include "replay_loop.hpp"

namespace sim::pcap {

int run_hesai_replay(int argc, char** argv);
int run_unitree_replay(int argc, char** argv);

// The end every family shares: the summary line, and the exit code with its one sentence.
int finish_replay(const apps::CommandLine& cli, const ReplayArgs& args, const ReplayResult& result,
                  const ReplayTarget& target, const std::string& decoded_as,
                  const apps::StopSignal& stop);

}  // namespace sim::pcap
