// SPDX-License-Identifier: Apache-2.0
// What the sim_record / sim_play tests share: the programs' paths, unique stream names that are
// removed afterwards, a reader thread that keeps every frame of a stream it sees, and the
// messages of an MCAP file decoded back into SIM frames.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <regex>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "sim/mcap/reader.hpp"
#include "sim/reader.hpp"
#include "sim/ros2/decode.hpp"
#include "sim_test/process.hpp"
#include "test_frames.hpp"

namespace sim::testing {

inline std::string unique_stream(const std::string& what) {
  static std::atomic<int> counter{0};
  return "/test_mcap_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" + what;
}

// Removes the streams at the end of a test, whatever happened.
struct StreamCleanup {
  std::vector<std::string> names;
  ~StreamCleanup() {
    for (const auto& n : names) (void)sim::destroy(n, true);
  }
};

struct Frame {
  std::uint64_t seq = 0;
  std::int64_t stamp_ns = 0;
  sim::Layout layout{};
  std::vector<std::byte> bytes;
};

// Opens a stream as soon as it exists and keeps a copy of every frame it reads, until stopped.
class FrameCollector {
 public:
  explicit FrameCollector(std::string name) : name_(std::move(name)), thread_([this] { run(); }) {}
  FrameCollector(const FrameCollector&) = delete;
  FrameCollector& operator=(const FrameCollector&) = delete;
  ~FrameCollector() { stop(); }

  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // Waits (bounded) until `count` frames arrived or the reader accounted for them as skipped.
  void wait_for(std::uint64_t count, std::chrono::seconds limit = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(mutex_);
        if (frames_.size() + skipped_ >= count) return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  std::vector<Frame> frames() {
    std::lock_guard lock(mutex_);
    return frames_;
  }
  std::uint64_t skipped() {
    std::lock_guard lock(mutex_);
    return skipped_;
  }

 private:
  void run() {
    std::optional<sim::Reader> reader;
    while (!stop_ && !reader) {
      auto opened = sim::Reader::open(name_);
      if (opened) {
        reader.emplace(std::move(*opened));
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
    std::vector<std::byte> buffer;
    while (!stop_ && reader) {
      buffer.resize(reader->capacity());
      sim::FrameInfo info;
      const auto status = reader->read_next(buffer, info, std::chrono::milliseconds(50));
      if (status != sim::ReadStatus::new_frame) continue;
      std::lock_guard lock(mutex_);
      frames_.push_back({info.seq, info.stamp_ns, info.layout,
                         {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(info.size)}});
      skipped_ = reader->stats().skipped;
    }
  }

  std::string name_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<Frame> frames_;
  std::uint64_t skipped_ = 0;
  std::thread thread_;
};

struct Recorded {
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;
  std::uint64_t publish_time = 0;
  std::int64_t header_stamp_ns = 0;
  std::vector<std::byte> frame;  // the SIM frame bytes the message carries
};

// The frame messages of every recorded stream (sim.stream, else the topic), in file order, with
// the frame bytes their ROS 2 messages carry.
inline std::map<std::string, std::vector<Recorded>> read_recording(const std::string& path) {
  std::map<std::string, std::vector<Recorded>> out;
  auto reader = sim::mcap::Reader::open(path);
  if (!reader) return out;
  while (auto m = reader->next()) {
    const auto& channel = reader->channels().at(m->header.channel_id);
    const auto* schema = reader->schema_of(channel);
    const auto stream = channel.metadata.find("sim.stream");
    const std::string key = stream != channel.metadata.end() ? stream->second : channel.topic;
    Recorded r{m->header.sequence, m->header.log_time, m->header.publish_time, 0, {}};
    if (schema && schema->name == "sensor_msgs/msg/Image") {
      auto image = sim::ros2::decode_image(m->data);
      if (!image) continue;
      r.header_stamp_ns = image->header.stamp.to_ns();
      r.frame.assign(image->data.begin(), image->data.end());
    } else if (schema && schema->name == "sensor_msgs/msg/PointCloud2") {
      auto cloud = sim::ros2::decode_point_cloud2(m->data);
      if (!cloud) continue;
      r.header_stamp_ns = cloud->header.stamp.to_ns();
      r.frame.assign(cloud->data.begin(), cloud->data.end());
    } else {
      continue;  // calibration, transforms: not frames
    }
    out[key].push_back(std::move(r));
  }
  return out;
}

// The recording both test suites make (needs SIM_RECORD, SIM_REPLAY_PCAP, MCAP_TEST_CAMERA and
// HESAI_DATA defined).
constexpr std::uint32_t kWidth = 320;
constexpr std::uint32_t kHeight = 200;
constexpr std::uint64_t kCameraFrames = 20;

inline std::uint64_t json_number(const std::string& json, const std::string& stream, const std::string& key) {
  const auto at = json.find("\"name\":\"" + stream + "\"");
  if (at == std::string::npos) return UINT64_MAX;
  std::smatch m;
  const std::string rest = json.substr(at);
  if (!std::regex_search(rest, m, std::regex("\"" + key + "\":([0-9]+)"))) return UINT64_MAX;
  return std::stoull(m[1]);
}

struct Recording {
  std::string camera;
  std::string lidar;
  std::string json;  // sim_record --json
  std::vector<sim::testing::Frame> live_lidar;
};

// Records the test camera and one pass of the Pandar64 capture into `path`.
inline Recording record(const std::string& path, const std::string& compression,
                 sim::testing::StreamCleanup& cleanup) {
  Recording r{unique_stream("cam"), unique_stream("lidar"), {}, {}};
  cleanup.names.insert(cleanup.names.end(), {r.camera, r.lidar});
  Process camera({MCAP_TEST_CAMERA, "--stream", r.camera, "--width", std::to_string(kWidth),
                  "--height", std::to_string(kHeight), "--frames", std::to_string(kCameraFrames),
                  "--fps", "30", "--wait-for-reader"});
  EXPECT_TRUE(camera.wait_for_line("ready"));
  Process recorder({SIM_RECORD, "-o", path, r.camera, r.lidar, "--wait-for-streams", "--json",
                    "--compression", compression});
  FrameCollector live(r.lidar);
  Process replay({SIM_REPLAY_PCAP, std::string(HESAI_DATA) + "/pandar64_dual.pcap", "--stream", r.lidar,
                  "--calibration", std::string(HESAI_DATA) + "/pandar64.calibration.csv", "--quiet"});
  EXPECT_TRUE(recorder.wait_for_line("recording")) << recorder.err();
  EXPECT_EQ(camera.wait(), 0) << camera.err();
  EXPECT_EQ(replay.wait(), 0) << replay.err();
  // No pause for the last frames: a stopped sim_record still takes each stream's newest frame.
  recorder.signal(SIGINT);
  EXPECT_EQ(recorder.wait(), 0) << recorder.err();
  live.stop();
  r.json = recorder.out();
  r.live_lidar = live.frames();
  return r;
}

}  // namespace sim::testing
