// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Velodyne family: what replay_main.cpp calls.
#pragma once

namespace sim::pcap {

int run_velodyne_replay(int argc, char** argv);

// Whether --model names a Velodyne model, or (without --model) the capture holds Velodyne data
// packets (1206 bytes, a product ID or the HDL-64E's block flags).
bool is_velodyne_replay(int argc, char** argv);

}  // namespace sim::pcap
