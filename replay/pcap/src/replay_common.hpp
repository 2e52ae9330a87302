// SPDX-License-Identifier: Apache-2.0
// What every family's replay shares (below the families, above the loop): the datagrams the
// family detection reads, and the end of a replay.
#pragma once

#include <string>

#include "replay_loop.hpp"

namespace sim::pcap {

// --port and --filter as the command line gives them, before it is parsed: the family detection
// reads the datagrams the user chose to reach the sensor (an unparsable port: none).
CaptureOptions detection_options(int argc, char** argv);

// The end every family shares: the summary line, and the exit code with its one sentence.
int finish_replay(const apps::CommandLine& cli, const ReplayArgs& args, const ReplayResult& result,
                  const ReplayTarget& target, const std::string& decoded_as,
                  const apps::StopSignal& stop);

}  // namespace sim::pcap
