// SPDX-License-Identifier: Apache-2.0
// sim_replay_pcap's Velodyne family: a row of the table in families.cpp.
#pragma once

#include "family.hpp"

namespace sim::pcap {

// --model a Velodyne model, a Velodyne calibration (ros-drivers YAML, db.xml), or Velodyne data
// packets (1206 bytes, a product ID or the HDL-64E's block flags) among the first datagrams.
Claim claim_velodyne(const Request& request, const Sniff& sniff);
int run_velodyne(const Request& request, Sniff& sniff);

}  // namespace sim::pcap
