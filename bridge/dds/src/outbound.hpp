// SPDX-License-Identifier: Apache-2.0
// SIM → DDS for one stream: a thread that follows the stream (it may appear later, its writer may
// restart, its region may be replaced), and for each new frame, only while a remote reader is
// matched, serializes it from the borrowed slot into a DDS message (the one copy) and writes it.
// While nobody listens it only looks at the stream a few times a second (review L9).
//
// Topics (docs/bridge.md, "Topics"): points on <stream>; images on <stream>/image_raw, JPEG on
// <stream>/image_raw/compressed (mjpeg streams, and --compress), the calibration as
// sensor_msgs/CameraInfo on <stream>/camera_info beside every image with the image's stamp and
// frame_id: the layout image_transport's CameraSubscriber and Foxglove pair without remapping.
// The stream's sensor mounting goes to /tf_static (StaticTransforms), its clock to /diagnostics
// (ClockDiagnostics, read once a second whether or not anyone reads the frames).
#pragma once

#include <atomic>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "clock_diagnostics.hpp"
#include "counters.hpp"
#include "dds_session.hpp"
#include "sim/reader.hpp"
#include "static_transforms.hpp"

namespace sim::bridge {

struct OutboundOptions {
  std::string stream;       // "/camera_front"
  std::string topic;        // the topics' base name, by default the stream's name
  std::string frame_id;     // --frame-id; by default the sensor's frame, else the stream name
                            // without its slash
  double max_rate_hz = 0;   // 0: every frame
  std::optional<int> jpeg_quality;  // --compress: also CompressedImage on <topic>/image_raw/compressed
  QosChoice qos;
  Trust trust{};            // whose regions to read (--trust-owner, --trust-group)
};

// Every ROS topic the Outbound of `options` may publish (which ones depends on the stream's
// layout, known once it is open).
std::vector<std::string> published_topics(const OutboundOptions& options);

// The ROS topic the frames of `options`' stream go to, by the stream's layout now; while the
// stream does not exist, the base name and "[/image_raw]" (images go there, points to the base).
std::string announced_topic(const OutboundOptions& options);

class Outbound {
 public:
  Outbound(DdsSession& session, StaticTransforms& transforms, ClockDiagnostics& clocks,
           OutboundOptions options);
  ~Outbound();  // stop()
  Outbound(const Outbound&) = delete;
  Outbound& operator=(const Outbound&) = delete;

  // Stops and joins the thread (its counters stay readable).
  void stop();

  const OutboundOptions& options() const noexcept { return options_; }
  Counters& raw() noexcept { return raw_; }
  Counters& compressed() noexcept { return compressed_; }
  Counters& camera_info() noexcept { return camera_info_; }
  // The ROS topic the frames go to now (the base name until the stream's layout is known).
  std::string raw_topic() const;
  std::string compressed_topic() const;
  std::string camera_info_topic() const;

 private:
  void run();
  void set_raw_topic(std::string topic);

  DdsSession& session_;
  StaticTransforms& transforms_;
  ClockDiagnostics& clocks_;
  OutboundOptions options_;
  Counters raw_;
  Counters compressed_;
  Counters camera_info_;
  mutable std::mutex topic_mutex_;
  std::string raw_topic_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sim::bridge
