// SPDX-License-Identifier: Apache-2.0
#include "frame_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sim/apps/status_line.hpp"

namespace sim::echo {

void Spread::add(double value) noexcept {
  ++count_;
  const double delta = value - mean_;
  mean_ += delta / static_cast<double>(count_);
  m2_ += delta * (value - mean_);
  min_ = std::min(min_, value);
  max_ = std::max(max_, value);
}

double Spread::stddev() const noexcept {
  return count_ > 1 ? std::sqrt(m2_ / static_cast<double>(count_ - 1)) : 0.0;
}

void FrameStats::add(const Frame& frame) {
  if (frames_ == 0) {
    first_seq_ = frame.seq;
    first_publish_ns_ = frame.publish_ns;
  } else {
    // Frames the writer published between two this reader took: replaced before it came.
    if (frame.seq > last_seq_ + 1) skipped_ += frame.seq - last_seq_ - 1;
    interval_ms_.add(static_cast<double>(frame.publish_ns - last_publish_ns_) / 1e6);
  }
  ++frames_;
  bytes_ += frame.size;
  last_seq_ = frame.seq;
  last_publish_ns_ = frame.publish_ns;
  const double latency = static_cast<double>(frame.read_ns - frame.publish_ns) / 1e3;
  latency_us_.add(latency);
  latencies_us_.push_back(latency);
  if (frame.stamp_ns != 0) {
    delay_us_.add(static_cast<double>(frame.read_realtime_ns - frame.stamp_ns) / 1e3);
  }
}

double FrameStats::rate_hz() const noexcept {
  const double span_s = static_cast<double>(last_publish_ns_ - first_publish_ns_) / 1e9;
  // Frames published over the span, skipped ones included: the stream's rate, not ours.
  const double intervals = static_cast<double>(last_seq_ - first_seq_);
  return frames_ > 1 && span_s > 0 ? intervals / span_s : 0.0;
}

double FrameStats::bandwidth_bytes_per_s() const noexcept {
  const double span_s = static_cast<double>(last_publish_ns_ - first_publish_ns_) / 1e9;
  if (frames_ < 2 || span_s <= 0) return 0.0;
  // Bytes of every frame after the first, over the time they took to come.
  const double per_frame = static_cast<double>(bytes_) / static_cast<double>(frames_);
  return per_frame * rate_hz();
}

double FrameStats::latency_percentile_us(double p) const {
  if (latencies_us_.empty()) return 0;
  std::vector<double> sorted = latencies_us_;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(k), sorted.end());
  return sorted[k];
}

std::string FrameStats::describe() const {
  char text[512];
  std::snprintf(text, sizeof text,
                "frames %llu  rate %.1f Hz (interval min %.2f max %.2f std %.2f ms)  "
                "latency p50 %.0f p99 %.0f max %.0f us  delay mean %.0f us  bandwidth %s  "
                "skipped %llu",
                static_cast<unsigned long long>(frames_), rate_hz(), interval_ms_.min(),
                interval_ms_.max(), interval_ms_.stddev(), latency_percentile_us(0.5),
                latency_percentile_us(0.99), latency_us_.max(), delay_us_.mean(),
                sim::apps::bandwidth(bandwidth_bytes_per_s()).c_str(),
                static_cast<unsigned long long>(skipped_));
  return text;
}

std::string FrameStats::json_fields() const {
  char text[768];
  std::snprintf(
      text, sizeof text,
      "\"frames\":%llu,\"skipped\":%llu,\"last_seq\":%llu,\"rate_hz\":%.3f,"
      "\"interval_ms\":{\"min\":%.3f,\"max\":%.3f,\"std\":%.3f},"
      "\"latency_us\":{\"min\":%.1f,\"mean\":%.1f,\"p50\":%.1f,\"p99\":%.1f,\"max\":%.1f},"
      "\"delay_us\":{\"min\":%.1f,\"mean\":%.1f,\"max\":%.1f},\"bandwidth_bytes_per_s\":%.0f",
      static_cast<unsigned long long>(frames_), static_cast<unsigned long long>(skipped_),
      static_cast<unsigned long long>(last_seq_), rate_hz(), interval_ms_.min(),
      interval_ms_.max(), interval_ms_.stddev(), latency_us_.min(), latency_us_.mean(),
      latency_percentile_us(0.5), latency_percentile_us(0.99), latency_us_.max(),
      delay_us_.min(), delay_us_.mean(), delay_us_.max(), bandwidth_bytes_per_s());
  return text;
}

}  // namespace sim::echo
