// SPDX-License-Identifier: Apache-2.0
#include "stream_watch.hpp"

#include <algorithm>
#include <chrono>

#include "sim/clock.hpp"

namespace sim::ls {

StreamWatch::StreamWatch(Reader reader) : reader_(std::move(reader)) {
  thread_ = std::thread([this] { run(); });
}

StreamWatch::~StreamWatch() {
  stop_.store(true);
  thread_.join();
}

WatchSample StreamWatch::take() {
  std::lock_guard lock(mutex_);
  return std::exchange(sample_, WatchSample{});
}

void StreamWatch::run() {
  // Frames published before the view opened are not counted.
  const std::int64_t opened_ns = monotonic_ns();
  while (!stop_.load()) {
    if (reader_.wait(std::chrono::milliseconds(100)) != ReadStatus::new_frame) continue;
    const Borrow borrow = reader_.borrow();
    if (borrow.status() != ReadStatus::new_frame) continue;
    const FrameInfo& info = borrow.info();
    const double latency_us = static_cast<double>(monotonic_ns() - info.publish_ns) / 1e3;
    if (info.publish_ns < opened_ns) {
      last_seq_ = info.seq;
      continue;
    }
    std::lock_guard lock(mutex_);
    ++sample_.frames;
    sample_.bytes += info.size;
    if (last_seq_ != 0 && info.seq > last_seq_ + 1) sample_.skipped += info.seq - last_seq_ - 1;
    last_seq_ = info.seq;
    sample_.latency_us_sum += latency_us;
    sample_.latency_us_max = std::max(sample_.latency_us_max, latency_us);
  }
}

}  // namespace sim::ls
