// SPDX-License-Identifier: Apache-2.0
// The table of sim_replay_pcap's families (families.cpp) and the choice among them.
#pragma once

#include <span>

#include "family.hpp"

namespace sim::pcap {

// Every family, the fallback first.
std::span<const Family> families() noexcept;

// The family with the strongest claim on the capture (ties: the earlier row). When none claims
// it (no --model or calibration of a family, no packet of one among the first datagrams, or a
// capture that cannot be read), the first row replays it: its detection explains the file.
const Family& claimant(const Request& request, const Sniff& sniff);

}  // namespace sim::pcap
