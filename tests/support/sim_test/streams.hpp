// SPDX-License-Identifier: Apache-2.0
// Streams in tests: names no other test (or test process) uses at the same time, guards that
// remove what a test created however it ends, and waiting for a stream another process creates.
#pragma once

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "sim/reader.hpp"

namespace sim::testing {

// "/test_<what>_<pid>_<n>": unique across the tests running in parallel.
inline std::string unique_name(const std::string& what) {
  static std::atomic<int> counter{0};
  return "/test_" + what + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

// Removes the streams when the test ends, however it ends (gone already is fine).
struct StreamGuard {
  StreamGuard() = default;
  explicit StreamGuard(std::string stream) : name(std::move(stream)) {}
  StreamGuard(const StreamGuard&) = delete;
  StreamGuard& operator=(const StreamGuard&) = delete;

  std::string name;
  std::vector<std::string> names;  // more streams the test created (an IMU stream, …)
  ~StreamGuard() {
    if (!name.empty()) (void)sim::destroy(name, /*force=*/true);
    for (const auto& n : names) (void)sim::destroy(n, /*force=*/true);
  }
};

// Opens the stream once another process has created it; nullopt after `timeout` (a hang guard,
// not a timing check).
inline std::optional<Reader> wait_for_stream(const std::string& name,
                                             std::chrono::milliseconds timeout =
                                                 std::chrono::milliseconds(30'000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto reader = Reader::open(name)) return std::move(*reader);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return std::nullopt;
}

}  // namespace sim::testing
