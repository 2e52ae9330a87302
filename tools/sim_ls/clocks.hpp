// SPDX-License-Identifier: Apache-2.0
// sim_ls --clocks: the host's clock and every stream's side by side, and which streams can be
// paired by their stamps at a given tolerance (sim::pairing_problem).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/reader.hpp"

namespace sim::ls {

struct ClockRow {
  std::string name;
  std::optional<ClockStatus> clock;
  std::string problem;  // why `clock` is empty: damaged, or "" when the writer reports none
};

// Whether two streams' stamps can be paired, and if not why.
struct Pairing {
  std::string first, second;
  std::string refusal;  // empty: they can
};
std::vector<Pairing> pairings(const std::vector<ClockRow>& rows, std::int64_t tolerance_ns);

// The view for people: the host's line, a table of the streams' clocks, the pairings.
void print_clocks_table(const ClockStatus& host, const std::vector<ClockRow>& rows,
                        std::int64_t tolerance_ns);
// For scripts: {"host":{…}} and {"tolerance_ns":…,"pairs":[…]}, one line each (the streams' own
// objects are sim_ls --json's, printed by the caller).
void print_host_json(const ClockStatus& host);
void print_pairs_json(const std::vector<ClockRow>& rows, std::int64_t tolerance_ns);

// True when any stream's verdict is error: sim_ls --clocks then exits 1.
bool any_clock_in_error(const std::vector<ClockRow>& rows);

}  // namespace sim::ls
