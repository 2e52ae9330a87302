// SPDX-License-Identifier: Apache-2.0
// DDS → SIM for one topic: a thread that waits until a remote writer of the topic is discovered
// (which also tells which of the three messages it carries), then takes each message and decodes
// it straight into a loaned slot of a local SIM stream. The stream's layout follows the
// messages: a change of size or encoding replaces the region, as a writer with a new layout does.
// Malformed messages are dropped, counted and told in one sentence; nothing bad is published,
// and a message is checked whole before the stream is touched.
//
// The stream's sensor description follows ROS 2 too: an image topic's sibling camera_info
// (<ns>/camera_info) gives the calibration, /tf_static the mounting of the images' frame_id
// (Writer::set_sensor_info).
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <thread>

#include "counters.hpp"
#include "dds_session.hpp"
#include "ros_message_type.hpp"
#include "sim/writer.hpp"
#include "static_transforms.hpp"

namespace sim::bridge {

struct InboundOptions {
  std::string topic;   // ROS topic on DDS, "/remote_camera"
  std::string stream;  // local SIM stream, by default the topic's name
  QosChoice qos;
};

class Inbound final : private MessageSink {
 public:
  Inbound(DdsSession& session, RemoteTransforms& transforms, InboundOptions options);
  ~Inbound();  // stop()
  Inbound(const Inbound&) = delete;
  Inbound& operator=(const Inbound&) = delete;

  void stop();  // stops and joins the thread (its counters stay readable)
  const InboundOptions& options() const noexcept { return options_; }
  Counters& counters() noexcept { return counters_; }

 private:
  // Receives the camera_info messages of the image topic.
  struct CameraInfoSink final : MessageSink {
    Inbound* inbound = nullptr;
    void deliver(std::span<const std::byte> message) override;
  };

  void run();
  void take_all(eprosima::fastdds::dds::DataReader* reader, MessageSink* sink);
  void tell_mismatches(const std::string& dds_topic);
  void deliver(std::span<const std::byte> message) override;
  void deliver_image(std::span<const std::byte> message);
  void deliver_compressed(std::span<const std::byte> message);
  void deliver_cloud(std::span<const std::byte> message);
  // Publishes `bytes` (or what `fill` writes into the loan) as one frame.
  template <typename Fill>
  void publish(Writer& writer, std::uint64_t bytes, std::int64_t stamp_ns, Fill&& fill);
  // The SIM writer for frames of `layout` needing `bytes`; replaces the stream when the layout
  // changes or the frame outgrew the slots. nullptr (with the reason counted) if it cannot.
  Writer* writer_for(const Layout& layout, std::uint64_t bytes, std::uint64_t capacity);
  void drop(const std::string& sentence);
  // The sensor description from the frame_id of the last message, the calibration and
  // /tf_static; given to the writer when it changed.
  void update_sensor();
  void note_frame_id(std::string_view frame_id);

  DdsSession& session_;
  RemoteTransforms& transforms_;
  InboundOptions options_;
  Counters counters_;
  ros2::MessageType type_ = ros2::MessageType::image;
  std::optional<Writer> writer_;
  std::string frame_id_;                        // of the last message
  std::optional<CameraCalibration> calibration_;  // from camera_info
  std::optional<SensorInfo> sensor_;            // what the writer has (accepted by it)
  std::optional<SensorInfo> offered_;           // the last built from ROS 2, as built
  bool sensor_check_due_ = false;
  std::int64_t next_sensor_check_ns_ = 0;
  CameraInfoSink camera_info_sink_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sim::bridge
