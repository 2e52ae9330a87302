// SPDX-License-Identifier: Apache-2.0
// Test-only: a LiDAR stream another process writes (a replay, a live driver), as the tools tests
// of every family read it: wait for the stream to appear, then take its next frames.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "sim/lidar_point.hpp"
#include "sim/reader.hpp"

namespace lidar_test {

// Opens the stream once the other process has created it; after `limit` (a bound against hangs,
// not a timing check) the last error, which says why.
inline sim::Expected<sim::Reader> open_when_created(const std::string& name,
                                                    std::chrono::milliseconds limit = std::chrono::seconds(30)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  for (;;) {
    auto reader = sim::Reader::open(name);
    if (reader || std::chrono::steady_clock::now() > deadline) return reader;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// A frame as a reader took it.
struct ReceivedFrame {
  std::vector<sim::LidarPoint> points;
  std::int64_t stamp_ns = 0;
  std::uint64_t seq = 0;
  std::int64_t receive_ns = 0;  // host time of the frame's first packet
};

// The next `count` frames (fewer when the generous `limit` against hangs passed first).
inline std::vector<ReceivedFrame> receive_frames(sim::Reader& reader, std::size_t count,
                                                 std::chrono::milliseconds limit = std::chrono::seconds(60)) {
  std::vector<std::byte> buffer(reader.capacity());
  std::vector<ReceivedFrame> frames;
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (frames.size() < count && std::chrono::steady_clock::now() < deadline) {
    sim::FrameInfo info;
    if (reader.read_next(buffer, info, std::chrono::milliseconds(100)) != sim::ReadStatus::new_frame) continue;
    ReceivedFrame f;
    f.points.resize(info.size / sizeof(sim::LidarPoint));
    std::memcpy(f.points.data(), buffer.data(), f.points.size() * sizeof(sim::LidarPoint));
    f.stamp_ns = info.stamp_ns;
    f.seq = info.seq;
    f.receive_ns = info.receive_ns;
    frames.push_back(std::move(f));
  }
  return frames;
}

}  // namespace lidar_test
