// SPDX-License-Identifier: Apache-2.0
// What sim_echo --stats measures over a window of frames: the rate with the spread of the
// intervals between frames (as `ros2 topic hz` shows it), latency (publish -> read, on
// CLOCK_MONOTONIC), delay (the sensor's stamp -> read, on CLOCK_REALTIME), bandwidth and the
// frames that were replaced before this reader could take them (skips).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace sim::echo {

// Count, min, max, mean and standard deviation of a series, in one pass (Welford).
class Spread {
 public:
  void add(double value) noexcept;
  std::uint64_t count() const noexcept { return count_; }
  double min() const noexcept { return count_ ? min_ : 0; }
  double max() const noexcept { return count_ ? max_ : 0; }
  double mean() const noexcept { return mean_; }
  double stddev() const noexcept;

 private:
  std::uint64_t count_ = 0;
  double mean_ = 0;
  double m2_ = 0;
  double min_ = std::numeric_limits<double>::max();
  double max_ = std::numeric_limits<double>::lowest();
};

struct Frame {
  std::uint64_t seq = 0;
  std::uint64_t size = 0;
  std::int64_t publish_ns = 0;  // CLOCK_MONOTONIC
  std::int64_t read_ns = 0;     // CLOCK_MONOTONIC
  std::int64_t stamp_ns = 0;    // CLOCK_REALTIME, the sensor's
  std::int64_t read_realtime_ns = 0;
};

class FrameStats {
 public:
  void add(const Frame& frame);

  std::uint64_t frames() const noexcept { return frames_; }
  std::uint64_t skipped() const noexcept { return skipped_; }
  std::uint64_t last_seq() const noexcept { return last_seq_; }
  // Frames per second between the first and the last frame (by publish time); 0 below two.
  double rate_hz() const noexcept;
  double bandwidth_bytes_per_s() const noexcept;
  const Spread& interval_ms() const noexcept { return interval_ms_; }
  const Spread& latency_us() const noexcept { return latency_us_; }
  const Spread& delay_us() const noexcept { return delay_us_; }
  // The p-th percentile (0..1) of latency, us.
  double latency_percentile_us(double p) const;

  // "rate 100.0 Hz (interval min 9.9 max 10.1 std 0.0 ms)  latency p50 55 p99 90 max 120 us  …"
  std::string describe() const;
  // {"frames":…,"skipped":…,"rate_hz":…,"interval_ms":{…},"latency_us":{…},"delay_us":{…},…}
  std::string json_fields() const;

 private:
  std::uint64_t frames_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint64_t first_seq_ = 0;
  std::uint64_t last_seq_ = 0;
  std::int64_t first_publish_ns_ = 0;
  std::int64_t last_publish_ns_ = 0;
  Spread interval_ms_;
  Spread latency_us_;
  Spread delay_us_;
  std::vector<double> latencies_us_;
};

}  // namespace sim::echo
