// SPDX-License-Identifier: Apache-2.0
#include "clock_diagnostics.hpp"

#include <vector>

#include "ros_message_type.hpp"
#include "sim/clock.hpp"
#include "sim/ros2/diagnostics.hpp"

namespace sim::bridge {

ClockDiagnostics::ClockDiagnostics(DdsSession& session, std::chrono::milliseconds period)
    : session_(session), thread_([this, period] { run(period); }) {}

ClockDiagnostics::~ClockDiagnostics() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  session_.delete_writer(writer_);
}

void ClockDiagnostics::set(const std::string& stream, std::string hardware_id,
                           std::optional<ClockStatus> clock, bool writer_alive) {
  std::lock_guard lock(mutex_);
  entries_[stream] = Entry{std::move(hardware_id), std::move(clock), writer_alive};
}

void ClockDiagnostics::writer_gone(const std::string& stream) {
  std::lock_guard lock(mutex_);
  const auto it = entries_.find(stream);
  if (it != entries_.end()) it->second.writer_alive = false;
}

void ClockDiagnostics::run(std::chrono::milliseconds period) {
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, period, [this] { return stopping_; })) {
    if (!entries_.empty()) publish();
  }
}

void ClockDiagnostics::publish() {
  if (writer_ == nullptr) {
    std::string error;
    // diagnostic_updater's publisher: reliable, volatile (the aggregator subscribes reliable).
    writer_ = session_.create_writer(ros2::dds_topic_name(diagnostics_topic),
                                     ros2::diagnostic_array_dds_type_name,
                                     QosChoice{.reliable = true, .depth = 10}, error);
    if (writer_ == nullptr) {
      counters_.problem(error);
      return;
    }
    counters_.connected.store(true);
  }
  ros2::DiagnosticArray array;
  array.stamp = ros2::Time::from_ns(realtime_ns());
  for (const auto& [stream, e] : entries_) {
    array.status.push_back(ros2::clock_diagnostic(stream, e.hardware_id, e.clock, e.writer_alive));
  }
  auto bytes = ros2::encode_diagnostic_array(array);
  if (!bytes) {
    counters_.count(counters_.failed);
    counters_.problem(std::string(diagnostics_topic) + ": " + bytes.error().message);
    return;
  }
  SerializedMessage message{*bytes};
  counters_.count(counters_.serialized);
  counters_.count(writer_->write(&message) ? counters_.bridged : counters_.failed);
}

}  // namespace sim::bridge
