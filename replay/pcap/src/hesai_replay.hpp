// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Hesai family: what replay_main.cpp calls.
#pragma once

namespace sim::pcap {

int run_hesai_replay(int argc, char** argv);

}  // namespace sim::pcap
