// SPDX-License-Identifier: Apache-2.0
// The families sim_replay_pcap replays, each with its own command line on apps/common.
#pragma once

#include <string>

#include "replay_loop.hpp"

namespace sim::pcap {

int run_hesai_replay(int argc, char** argv);
int run_unitree_replay(int argc, char** argv);
int run_ouster_replay(int argc, char** argv);
int run_velodyne_replay(int argc, char** argv);

// Whether --model names a Velodyne model, or (without --model) the capture holds Velodyne data
// packets (1206 bytes, a product ID or the HDL-64E's block flags).
bool is_velodyne_replay(int argc, char** argv);

// Whether the capture named on the command line holds Ouster lidar packets and no Hesai ones
// (Ouster packets carry no family mark: their sizes and column indices tell).
bool is_ouster_capture(int argc, char** argv);

// --port and --filter as the command line gives them, before it is parsed: the family detection
// reads the datagrams the user chose to reach the sensor (an unparsable port: none).
CaptureOptions detection_options(int argc, char** argv);

// The end every family shares: the summary line, and the exit code with its one sentence.
int finish_replay(const apps::CommandLine& cli, const ReplayArgs& args, const ReplayResult& result,
                  const ReplayTarget& target, const std::string& decoded_as,
                  const apps::StopSignal& stop);

}  // namespace sim::pcap
