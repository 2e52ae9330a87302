// SPDX-License-Identifier: Apache-2.0
// The live view of one stream (sim_ls --watch): a thread that sleeps on the stream like any
// reader, takes each new frame in place (a borrow, no copy) and counts what a person watching
// wants to know: frames, bytes, latency (publish -> this view's read) and frames it could not
// see (replaced before it woke).
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "sim/reader.hpp"

namespace sim::ls {

struct WatchSample {
  std::uint64_t frames = 0;
  std::uint64_t bytes = 0;
  std::uint64_t skipped = 0;
  double latency_us_sum = 0;
  double latency_us_max = 0;
};

class StreamWatch {
 public:
  explicit StreamWatch(Reader reader);
  StreamWatch(const StreamWatch&) = delete;
  StreamWatch& operator=(const StreamWatch&) = delete;
  ~StreamWatch();

  // What was counted since the last call.
  WatchSample take();

 private:
  void run();
  Reader reader_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  WatchSample sample_;
  std::uint64_t last_seq_ = 0;
  std::thread thread_;
};

}  // namespace sim::ls
