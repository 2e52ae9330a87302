// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Ouster family: a row of the table in families.cpp.
#pragma once

#include "family.hpp"

namespace sim::pcap {

// A metadata JSON (--calibration FILE.json), or Ouster lidar packets among the first datagrams
// (they carry no family mark: their sizes and column indices tell).
Claim claim_ouster(const Request& request, const Sniff& sniff);
int run_ouster(const Request& request, Sniff& sniff);

}  // namespace sim::pcap
