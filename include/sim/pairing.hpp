// SPDX-License-Identifier: Apache-2.0
// Pairs frames of two streams by sensor time, for camera + LiDAR fusion. Like ROS 2
// message_filters' ApproximateTime, but freshness first: of all pairs whose stamps lie within the
// tolerance, it returns the one whose older frame is newest (ties: the closer pair), and each frame
// is used at most once. Pure data structure: feed it what your readers returned.
//
//   sim::ApproximatePairer<CameraFrame, Scan> pairer(std::chrono::milliseconds(20));
//   pairer.add_first(info.stamp_ns, std::move(image));
//   pairer.add_second(info.stamp_ns, std::move(scan));
//   if (auto pair = pairer.take()) fuse(pair->first, pair->second);
//
// Stamps are only as good as their clocks: give the pairer both streams' clock records
// (Reader::clock(), when FrameInfo::clock_generation changes) and it refuses to pair while they
// are known to disagree beyond its tolerance (refusal() says why), unless told to ignore clocks.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "sim/clock_status.hpp"

namespace sim {

template <typename First, typename Second>
class ApproximatePairer {
 public:
  // The values are carried as given: a frame copy, a shared_ptr, an index into your buffers.
  struct Pair {
    std::int64_t first_stamp_ns;
    First first;
    std::int64_t second_stamp_ns;
    Second second;
  };

  // `tolerance`: the largest stamp difference of a pair. `history`: frames kept per stream
  // (older ones drop out); a few periods of the slower stream are enough.
  explicit ApproximatePairer(std::chrono::nanoseconds tolerance, std::size_t history = 8)
      : tolerance_ns_(tolerance.count()), history_(history == 0 ? 1 : history) {}

  // The streams' clocks as their records say now (names for the refusal's sentence). While
  // they are known to disagree (sim::pairing_problem), take() pairs nothing and refusal() says
  // why; ignore_clocks(true) pairs regardless (you know better, e.g. both stamped on arrival).
  void set_clocks(std::string_view first_name, const ClockStatus& first, std::string_view second_name,
                  const ClockStatus& second) {
    refusal_ = pairing_problem(first_name, first, second_name, second, tolerance_ns_);
  }
  void ignore_clocks(bool ignore) noexcept { ignore_clocks_ = ignore; }
  // Why take() pairs nothing although stamps may match; empty when it pairs.
  const std::string& refusal() const noexcept { return ignore_clocks_ ? kNoRefusal : refusal_; }

  void add_first(std::int64_t stamp_ns, First value) { add(firsts_, stamp_ns, std::move(value)); }
  void add_second(std::int64_t stamp_ns, Second value) { add(seconds_, stamp_ns, std::move(value)); }

  // The freshest pair within the tolerance, removed with every older frame of both streams (a
  // fused result newer than them exists now); nothing if no pair is within the tolerance.
  std::optional<Pair> take() {
    if (!refusal().empty()) return std::nullopt;
    std::optional<std::pair<std::size_t, std::size_t>> best;
    std::int64_t best_older = 0, best_gap = 0;
    for (std::size_t i = 0; i < firsts_.size(); ++i) {
      for (std::size_t j = 0; j < seconds_.size(); ++j) {
        const std::int64_t a = firsts_[i].first, b = seconds_[j].first;
        const std::int64_t gap = a > b ? a - b : b - a;
        if (gap > tolerance_ns_) continue;
        const std::int64_t older = a < b ? a : b;
        if (!best || older > best_older || (older == best_older && gap < best_gap)) {
          best = std::pair{i, j};
          best_older = older;
          best_gap = gap;
        }
      }
    }
    if (!best) return std::nullopt;
    auto& [fs, fv] = firsts_[best->first];
    auto& [ss, sv] = seconds_[best->second];
    Pair out{fs, std::move(fv), ss, std::move(sv)};
    firsts_.erase(firsts_.begin(), firsts_.begin() + static_cast<std::ptrdiff_t>(best->first) + 1);
    seconds_.erase(seconds_.begin(), seconds_.begin() + static_cast<std::ptrdiff_t>(best->second) + 1);
    return out;
  }

  std::size_t pending_first() const noexcept { return firsts_.size(); }
  std::size_t pending_second() const noexcept { return seconds_.size(); }

 private:
  template <typename T>
  void add(std::deque<std::pair<std::int64_t, T>>& queue, std::int64_t stamp_ns, T value) {
    // Frames come in stamp order from a reader; one out of order (a restarted sensor) starts over.
    if (!queue.empty() && stamp_ns <= queue.back().first) queue.clear();
    queue.emplace_back(stamp_ns, std::move(value));
    while (queue.size() > history_) queue.pop_front();
  }

  inline static const std::string kNoRefusal{};
  std::int64_t tolerance_ns_;
  std::size_t history_;
  std::string refusal_{};
  bool ignore_clocks_ = false;
  std::deque<std::pair<std::int64_t, First>> firsts_;
  std::deque<std::pair<std::int64_t, Second>> seconds_;
};

}  // namespace sim
