// SPDX-License-Identifier: Apache-2.0
// The latency summary of one configuration and run, pooled over all of its readers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace sim::bench {

struct LatencySummary {
  double min_us = std::numeric_limits<double>::quiet_NaN();
  double mean_us = min_us, p50_us = min_us, p95_us = min_us, p99_us = min_us, p999_us = min_us;
  double max_us = min_us, std_us = min_us;
  std::size_t count = 0;
};

// Nearest-rank percentile of sorted samples (p in 0..100).
inline double percentile(const std::vector<std::int64_t>& sorted, double p) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double rank = std::ceil(p / 100.0 * static_cast<double>(sorted.size()));
  const std::size_t index = rank < 1 ? 0 : static_cast<std::size_t>(rank) - 1;
  return static_cast<double>(sorted[std::min(index, sorted.size() - 1)]);
}

inline LatencySummary summarize(std::vector<std::int64_t> samples_ns) {
  LatencySummary s;
  s.count = samples_ns.size();
  if (samples_ns.empty()) return s;
  std::sort(samples_ns.begin(), samples_ns.end());
  double sum = 0;
  for (const auto v : samples_ns) sum += static_cast<double>(v);
  const double mean = sum / static_cast<double>(samples_ns.size());
  double squares = 0;
  for (const auto v : samples_ns) squares += (static_cast<double>(v) - mean) * (static_cast<double>(v) - mean);
  const double n = static_cast<double>(samples_ns.size());
  s.min_us = static_cast<double>(samples_ns.front()) / 1e3;
  s.max_us = static_cast<double>(samples_ns.back()) / 1e3;
  s.mean_us = mean / 1e3;
  s.std_us = (n > 1 ? std::sqrt(squares / (n - 1)) : 0.0) / 1e3;
  s.p50_us = percentile(samples_ns, 50) / 1e3;
  s.p95_us = percentile(samples_ns, 95) / 1e3;
  s.p99_us = percentile(samples_ns, 99) / 1e3;
  s.p999_us = percentile(samples_ns, 99.9) / 1e3;
  return s;
}

}  // namespace sim::bench
