// SPDX-License-Identifier: Apache-2.0
// Records SIM streams into an MCAP file: one thread per stream borrows each new frame in place
// and serializes it straight from the slot into a ROS 2 message (sim::ros2), then hands it to
// one writer thread that chunks, compresses and writes (sim::mcap::Writer). A full queue makes
// the stream threads wait, so their readers skip frames: those are counted as missed, never
// silently lost.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/mcap/writer.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim::record {

struct RecorderOptions {
  std::string path;                  // the .mcap file
  std::vector<std::string> streams;  // SIM stream names ("/lidar_top")
  mcap::WriterOptions writer{};
  std::uint64_t queue_bytes = 256u << 20;  // messages waiting for the writer thread, at most
  Trust trust{};                           // whose regions to read (--trust-owner, --trust-group)
};

struct StreamCounters {
  std::string name;
  std::uint64_t frames = 0;     // recorded
  std::uint64_t bytes = 0;      // of serialized messages
  std::uint64_t missed = 0;     // published but not recorded (the reader skipped or was lapped)
  std::uint64_t unrecordable = 0;  // frames with no ROS 2 message (see problem)
};

struct RecorderProgress {
  std::vector<StreamCounters> streams;
  std::uint64_t file_bytes = 0;
  std::uint64_t queued_bytes = 0;
};

class Recorder {
 public:
  // Opens every stream and the file and starts recording; fails with one sentence when a stream
  // or the file cannot be opened.
  static Expected<Recorder> start(const RecorderOptions& options);

  Recorder(Recorder&&) noexcept;
  Recorder& operator=(Recorder&&) noexcept;
  ~Recorder();

  RecorderProgress progress() const;
  // The first thing that went wrong while recording (write error, unrecordable frame), or empty.
  std::string problem() const;
  // True once recording cannot go on (the file could not be written).
  bool failed() const;

  // Stops the stream threads, writes what is queued, closes the file (summary and footer).
  // Returns the final counters; problem() tells whether it all went well.
  RecorderProgress stop();

  struct Impl;

 private:
  explicit Recorder(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::record
