// SPDX-License-Identifier: Apache-2.0
#include "clocks.hpp"

#include <algorithm>
#include <cstdio>

#include "sim/apps/clock_text.hpp"
#include "sim/apps/sensor_text.hpp"

namespace sim::ls {
namespace {

ClockStatus effective(const ClockRow& row) { return apps::effective_clock({row.clock, row.problem}); }

std::string offset_text(const ClockStatus& c) {
  if (!c.offset_to_host_ns) return "-";
  std::string text = human_duration(*c.offset_to_host_ns);
  if (*c.offset_to_host_ns > 0) text.insert(text.begin(), '+');
  return text;
}

}  // namespace

std::vector<Pairing> pairings(const std::vector<ClockRow>& rows, std::int64_t tolerance_ns) {
  std::vector<Pairing> out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t j = i + 1; j < rows.size(); ++j) {
      out.push_back({rows[i].name, rows[j].name,
                     pairing_problem(rows[i].name, effective(rows[i]), rows[j].name, effective(rows[j]),
                                     tolerance_ns)});
    }
  }
  return out;
}

void print_clocks_table(const ClockStatus& host, const std::vector<ClockRow>& rows,
                        std::int64_t tolerance_ns) {
  std::printf("host: %s\n", summary(host).c_str());
  std::size_t width = 6;
  for (const auto& row : rows) width = std::max(width, row.name.size());
  const int w = static_cast<int>(width);
  std::printf("%-*s %-12s %-12s %14s %10s %-7s  %s\n", w, "STREAM", "SOURCE", "STATE", "OFFSET-TO-HOST",
              "SPREAD", "VERDICT", "PROBLEM");
  for (const auto& row : rows) {
    const ClockStatus c = effective(row);
    std::printf("%-*s %-12s %-12s %14s %10s %-7s  %s\n", w, row.name.c_str(), to_string(c.source),
                to_string(c.state), offset_text(c).c_str(),
                c.offset_to_host_ns ? ("±" + human_duration(c.spread_ns)).c_str() : "-",
                to_string(c.verdict), c.problem.c_str());
  }
  const auto pairs = pairings(rows, tolerance_ns);
  if (pairs.empty()) return;
  std::printf("pairs by stamp within %s:\n", human_duration(tolerance_ns).c_str());
  for (const auto& p : pairs) {
    std::printf("  %s + %s: %s\n", p.first.c_str(), p.second.c_str(),
                p.refusal.empty() ? "yes" : ("no: " + p.refusal).c_str());
  }
}

void print_host_json(const ClockStatus& host) {
  std::printf("{\"host\":%s}\n", apps::host_clock_json(host).c_str());
}

void print_pairs_json(const std::vector<ClockRow>& rows, std::int64_t tolerance_ns) {
  std::string pairs = "[";
  for (const auto& p : pairings(rows, tolerance_ns)) {
    if (pairs.size() > 1) pairs += ',';
    pairs += "{\"streams\":[" + apps::json_string(p.first) + "," + apps::json_string(p.second) +
             "],\"pairable\":" + (p.refusal.empty() ? "true" : "false") +
             ",\"reason\":" + apps::json_string(p.refusal) + "}";
  }
  std::printf("{\"tolerance_ns\":%lld,\"pairs\":%s]}\n", static_cast<long long>(tolerance_ns), pairs.c_str());
}

bool any_clock_in_error(const std::vector<ClockRow>& rows) {
  return std::any_of(rows.begin(), rows.end(),
                     [](const ClockRow& row) { return effective(row).verdict == ClockVerdict::error; });
}

}  // namespace sim::ls
