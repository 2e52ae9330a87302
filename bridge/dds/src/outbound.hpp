// SPDX-License-Identifier: Apache-2.0
// SIM → DDS for one stream: a thread that follows the stream (it may appear later, its writer may
// restart, its region may be replaced), and for each new frame, only while a remote reader is
// matched, serializes it from the borrowed slot into a DDS message (the one copy) and writes it.
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <thread>

#include "counters.hpp"
#include "dds_session.hpp"
#include "sim/reader.hpp"

namespace sim::bridge {

struct OutboundOptions {
  std::string stream;       // "/camera_front"
  std::string topic;        // ROS topic, by default the stream's name
  std::string frame_id;     // header.frame_id, by default the stream name without its slash
  double max_rate_hz = 0;   // 0: every frame
  std::optional<int> jpeg_quality;  // --compress: also CompressedImage on <topic>/compressed
  QosChoice qos;
  Trust trust{};            // whose regions to read (--trust-owner, --trust-group)
};

class Outbound {
 public:
  Outbound(DdsSession& session, OutboundOptions options);
  ~Outbound();  // stops and joins the thread
  Outbound(const Outbound&) = delete;
  Outbound& operator=(const Outbound&) = delete;

  const OutboundOptions& options() const noexcept { return options_; }
  Counters& raw() noexcept { return raw_; }
  Counters& compressed() noexcept { return compressed_; }

 private:
  void run();

  DdsSession& session_;
  OutboundOptions options_;
  Counters raw_;
  Counters compressed_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sim::bridge
