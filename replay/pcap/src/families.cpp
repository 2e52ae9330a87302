// SPDX-License-Identifier: Apache-2.0
#include "families.hpp"

#include <array>

#include "hesai_replay.hpp"
#include "ouster_replay.hpp"
#include "unitree_replay.hpp"
#include "velodyne_replay.hpp"

namespace sim::pcap {
namespace {

// One row per family: its name, its claim on a capture, its replay. Hesai is first: a capture
// no family claims is explained by the Hesai detection, which names the others it is not.
constexpr std::array table{
    Family{"Hesai", claim_hesai, run_hesai},
    Family{"Velodyne", claim_velodyne, run_velodyne},
    Family{"Ouster", claim_ouster, run_ouster},
    Family{"Unitree", claim_unitree, run_unitree},
};

}  // namespace

std::span<const Family> families() noexcept { return table; }

const Family& claimant(const Request& request, const Sniff& sniff) {
  const Family* best = &table.front();
  Claim strongest;
  for (const Family& family : table) {
    const Claim claim = family.claim(request, sniff);
    if (claim > strongest) {
      strongest = claim;
      best = &family;
    }
  }
  return *best;
}

}  // namespace sim::pcap
