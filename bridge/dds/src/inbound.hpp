// SPDX-License-Identifier: Apache-2.0
// DDS → SIM for one topic: a thread that waits until a remote writer of the topic is discovered
// (which also tells which of the three messages it carries), then takes each message and decodes
// it straight into a loaned slot of a local SIM stream. The stream's layout follows the
// messages: a change of size or encoding replaces the region, as a writer with a new layout does.
// Malformed messages are dropped, counted and told in one sentence; nothing bad is published.
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <thread>

#include "counters.hpp"
#include "dds_session.hpp"
#include "ros_message_type.hpp"
#include "sim/writer.hpp"

namespace sim::bridge {

struct InboundOptions {
  std::string topic;   // ROS topic on DDS, "/remote_camera"
  std::string stream;  // local SIM stream, by default the topic's name
  QosChoice qos;
};

class Inbound final : private MessageSink {
 public:
  Inbound(DdsSession& session, InboundOptions options);
  ~Inbound();  // stops and joins the thread
  Inbound(const Inbound&) = delete;
  Inbound& operator=(const Inbound&) = delete;

  const InboundOptions& options() const noexcept { return options_; }
  Counters& counters() noexcept { return counters_; }

 private:
  void run();
  void deliver(std::span<const std::byte> message) override;
  void deliver_image(std::span<const std::byte> message);
  void deliver_compressed(std::span<const std::byte> message);
  void deliver_cloud(std::span<const std::byte> message);
  // The SIM writer for frames of `layout` needing `bytes`; replaces the stream when the layout
  // changes or the frame outgrew the slots. nullptr (with the reason counted) if it cannot.
  Writer* writer_for(const Layout& layout, std::uint64_t bytes, std::uint64_t capacity);
  void drop(const std::string& sentence);

  DdsSession& session_;
  InboundOptions options_;
  Counters counters_;
  ros2::MessageType type_ = ros2::MessageType::image;
  std::optional<Writer> writer_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sim::bridge
