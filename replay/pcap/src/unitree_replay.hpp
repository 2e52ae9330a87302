// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Unitree family: a row of the table in families.cpp.
#pragma once

#include "family.hpp"

namespace sim::pcap {

// --model unitree-l1 or unitree-l2: the L1/L2 byte stream names no model of its own.
Claim claim_unitree(const Request& request, const Sniff& sniff);
int run_unitree(const Request& request, Sniff& sniff);

}  // namespace sim::pcap
