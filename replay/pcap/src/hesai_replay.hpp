// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Hesai family: a row of the table in families.cpp.
#pragma once

#include "family.hpp"

namespace sim::pcap {

// --model a Hesai model, or Hesai point-cloud packets among the first datagrams.
Claim claim_hesai(const Request& request, const Sniff& sniff);
int run_hesai(const Request& request, Sniff& sniff);

}  // namespace sim::pcap
