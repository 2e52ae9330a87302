// SPDX-License-Identifier: Apache-2.0
// /diagnostics: each published stream's clock (sim::ClockStatus) as ROS 2 diagnostics, one
// diagnostic_msgs/msg/DiagnosticArray a second with one DiagnosticStatus per stream (name
// "sim: <stream> clock"; sim/ros2/diagnostics.hpp has the levels and values), so that
// `ros2 topic echo /diagnostics`, rqt_robot_monitor, the diagnostic aggregator and Foxglove's
// Diagnostics panels show whether the stamps of each stream can be trusted. The Outbounds hand
// in what they read of their stream (set, writer_gone); a thread of its own publishes.
#pragma once

#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "counters.hpp"
#include "dds_session.hpp"
#include "sim/clock_status.hpp"

namespace sim::bridge {

inline constexpr const char* diagnostics_topic = "/diagnostics";

class ClockDiagnostics {
 public:
  // Publishes every `period` until destroyed (the first array once a stream was set).
  explicit ClockDiagnostics(DdsSession& session,
                            std::chrono::milliseconds period = std::chrono::milliseconds(1000));
  ~ClockDiagnostics();
  ClockDiagnostics(const ClockDiagnostics&) = delete;
  ClockDiagnostics& operator=(const ClockDiagnostics&) = delete;

  // What the Outbound of `stream` read last: the clock record (nullopt: the stream has none),
  // the sensor's serial or the stream name, whether the writer lives.
  void set(const std::string& stream, std::string hardware_id, std::optional<ClockStatus> clock,
           bool writer_alive);
  // The stream's writer stopped or its region went away: its status turns STALE (a stream never
  // set is left out).
  void writer_gone(const std::string& stream);

  Counters& counters() noexcept { return counters_; }

 private:
  struct Entry {
    std::string hardware_id;
    std::optional<ClockStatus> clock;
    bool writer_alive = true;
  };
  void run(std::chrono::milliseconds period);
  void publish();  // under mutex_

  DdsSession& session_;
  Counters counters_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::map<std::string, Entry> entries_;  // by stream
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace sim::bridge
