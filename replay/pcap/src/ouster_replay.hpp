// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Ouster family: what replay_main.cpp calls.
#pragma once

namespace sim::pcap {

int run_ouster_replay(int argc, char** argv);

// Whether the capture named on the command line holds Ouster lidar packets and no Hesai ones
// (Ouster packets carry no family mark: their sizes and column indices tell).
bool is_ouster_capture(int argc, char** argv);

}  // namespace sim::pcap
