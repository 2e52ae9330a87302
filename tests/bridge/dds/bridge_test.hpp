// SPDX-License-Identifier: Apache-2.0
// What the bridge tests share: the bridge as a process with --json, its counters, unique names,
// the skip when there is no private network, the DDS → SIM setup (the bridge subscribed, a Cyclone
// writer matched), messages to send, and waiting for what the bridge writes into SIM or tells.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cyclone.hpp"
#include "sim/reader.hpp"
#include "sim/writer.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace bridge_test {

using namespace std::chrono_literals;
using sim::testing::CycloneParticipant;
using sim::testing::CycloneWriter;
using sim::testing::EndpointQos;
using sim::testing::Process;
using sim::testing::StreamGuard;
using sim::testing::CycloneReader;

// The ROS 2 messages as idlc generated them (idl/sensor_msgs.idl).
using Cloud = sensor_msgs_msg_dds__PointCloud2_;
using Image = sensor_msgs_msg_dds__Image_;
using Compressed = sensor_msgs_msg_dds__CompressedImage_;
using CameraInfo = sensor_msgs_msg_dds__CameraInfo_;
using TfMessage = tf2_msgs_msg_dds__TFMessage_;
using Graph = rmw_dds_common_msg_dds__ParticipantEntitiesInfo_;

const std::string bridge_tool = SIM_DDS_BRIDGE;

// Set in main(): why this process has no private network (its tests then skip).
inline std::optional<std::string> g_skip_reason;

#define SKIP_WITHOUT_NETWORK() \
  if (g_skip_reason) GTEST_SKIP() << *g_skip_reason

// Every bridge test program's main(): into a private network namespace (loopback with
// multicast, so discovery never leaves the test), or a reason for the tests to skip.
inline int run_tests(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::on);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

inline std::string unique_name(const std::string& what) {
  return sim::testing::unique_name("bridge_" + what);
}

// A number out of the bridge's --json line for the topic `topic`: "\"bridged\":12".
inline long long json_counter(const std::string& line, const std::string& topic, const std::string& key) {
  const auto at = line.find("\"topic\":\"" + topic + "\"");
  if (at == std::string::npos) return -1;
  const auto k = line.find("\"" + key + "\":", at);
  if (k == std::string::npos) return -1;
  return std::stoll(line.substr(k + key.size() + 3));
}

// Reads the bridge's JSON lines until `topic`'s `key` reaches `at_least`; the last line read, or
// empty when the bridge ended or a minute passed (a hang guard, not a timing check).
inline std::string wait_counter(Process& bridge, const std::string& topic, const std::string& key,
                                long long at_least) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (std::chrono::steady_clock::now() < deadline) {
    auto line = bridge.wait_for_line("\"topics\"");
    if (!line) return {};
    if (json_counter(*line, topic, key) >= at_least) return *line;
  }
  return {};
}

inline std::int64_t stamp_of(const std_msgs_msg_dds__Header_& h) {
  return std::int64_t{h.stamp.sec} * 1'000'000'000 + h.stamp.nanosec;
}

inline Process start_bridge(std::vector<std::string> args) {
  std::vector<std::string> argv = {bridge_tool, "--json", "--status-period", "0.1", "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return Process(argv);
}

// Reads status reports until the bridge's stderr holds every one of `sentences` (they come with
// the reports); false when they are not there after 300 reports (a hang guard, not a timing check).
inline bool wait_until_told(Process& bridge, std::initializer_list<std::string> sentences) {
  const auto told = [&] {
    for (const std::string& sentence : sentences) {
      if (bridge.err().find(sentence) == std::string::npos) return false;
    }
    return true;
  };
  for (int i = 0; i < 300 && !told(); ++i) (void)bridge.wait_for_line("\"topics\"");
  return told();
}

// How a Subscription differs from the plain one.
struct SubscriptionOptions {
  std::vector<std::string> bridge_options;  // before --subscribe: --reliable, --reliable-subscribe
  EndpointQos writer_qos{};                 // ROS 2's sensor data (best effort) by default
  bool as_topic_equals_stream = false;      // --as TOPIC=STREAM instead of --as STREAM
};

// The DDS → SIM tests' setup: the bridge subscribed to a unique DDS topic and writing it into a
// unique SIM stream, and a Cyclone DDS writer of `type` on that topic in a participant of its own.
// A test waits for the match before it writes: ASSERT_TRUE(s.writer.wait_matched()) << s.bridge.err().
struct Subscription {
  Subscription(const std::string& what, const dds_topic_descriptor_t* type,
               const SubscriptionOptions& options = {})
      : topic(unique_name(what)),
        local(unique_name(what + "_local")),
        bridge(start_bridge(arguments(options))),
        writer(participant, type, "rt" + topic, options.writer_qos) {}

  const std::string topic;
  StreamGuard local;
  Process bridge;
  CycloneParticipant participant;
  CycloneWriter writer;

 private:
  std::vector<std::string> arguments(const SubscriptionOptions& options) const {
    std::vector<std::string> args = options.bridge_options;
    args.insert(args.end(), {"--subscribe", topic, "--as",
                             options.as_topic_equals_stream ? topic + "=" + local.name : local.name});
    return args;
  }
};

// A sensor_msgs Image whose pixels are all `fill`, stamped 1.7e9 s, in the frame `frame_id`.
struct ImageMessage {
  std::vector<std::uint8_t> pixels;
  sensor_msgs_msg_dds__Image_ image{};
  ImageMessage(std::uint32_t width, std::uint32_t height, const char* encoding, std::uint32_t step,
               std::uint8_t fill = 7, const char* frame_id = "cam")
      : pixels(std::size_t{step} * height, fill) {
    image.header.stamp = {1'700'000'000, 0};
    image.header.frame_id = const_cast<char*>(frame_id);
    image.width = width;
    image.height = height;
    image.encoding = const_cast<char*>(encoding);
    image.step = step;
    image.data._buffer = pixels.data();
    image.data._length = image.data._maximum = static_cast<std::uint32_t>(pixels.size());
  }
  ImageMessage(const ImageMessage&) = delete;  // the image points into its own pixels
  ImageMessage& operator=(const ImageMessage&) = delete;
};

inline sim::Expected<sim::Reader> open_when_created(const std::string& name) {
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  for (;;) {
    auto reader = sim::Reader::open(name);
    if (reader || std::chrono::steady_clock::now() > deadline) return reader;
    std::this_thread::sleep_for(5ms);
  }
}

// Publishes `sample` until the SIM reader has a frame newer than the last, and returns it
// (best effort may lose the first messages while the bridge's reader is still matching).
inline std::optional<std::pair<sim::FrameInfo, std::vector<std::byte>>> publish_until_seen(
    CycloneWriter& writer, const void* sample, sim::Reader& reader) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    writer.write(sample);
    std::vector<std::byte> buffer(reader.capacity());  // the region may have been replaced
    sim::FrameInfo info;
    if (reader.read_next(buffer, info, 300ms) == sim::ReadStatus::new_frame) {
      buffer.resize(info.size);
      return std::make_pair(info, buffer);
    }
  }
  return std::nullopt;
}

// A SIM writer in this process that publishes a frame every 30 ms (stamped 1.7e18 + n × 33.3 ms,
// each frame's bytes a pattern of its number) until it is destroyed: a live stream for the bridge
// to publish.
class FramePump {
 public:
  FramePump(sim::StreamSpec spec) : writer_(sim::Writer::create(spec)) {
    if (writer_) thread_ = std::thread([this] { run(); });
  }
  ~FramePump() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  bool ok() const { return writer_.has_value(); }
  std::string error() { return writer_ ? std::string{} : writer_.error().message; }
  static std::int64_t stamp_of_frame(std::uint64_t n) {
    return 1'700'000'000'000'000'000 + static_cast<std::int64_t>(n) * 33'333'333;
  }

 private:
  void run() {
    std::vector<std::byte> frame(writer_->layout().min_capacity());
    for (std::uint64_t n = 0; !stop_; ++n) {
      for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = std::byte(static_cast<std::uint8_t>(i + n));
      (void)writer_->write(frame, stamp_of_frame(n));
      std::this_thread::sleep_for(30ms);
    }
  }
  sim::Expected<sim::Writer> writer_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace bridge_test
