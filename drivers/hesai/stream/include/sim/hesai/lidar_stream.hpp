// SPDX-License-Identifier: Apache-2.0
// LidarStream: the one path from Hesai UDP payloads to a SIM stream, shared by the live driver
// (sim_lidar_hesai) and the capture replay (sim_replay_pcap), so a consumer cannot tell them
// apart. It owns the SIM writer and the FrameAssembler, keeps the assembler's output pointed at
// the writer's loaned slot (points are decoded straight into shared memory), and commits each
// completed revolution with the sensor time of its first point. No allocation per packet.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "sim/hesai/hesai.hpp"
#include "sim/lidar/frame_publisher.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/writer.hpp"

namespace sim::hesai {

struct LidarStreamConfig {
  std::string stream = "/lidar_top";
  std::filesystem::path calibration;               // the unit's angle-correction CSV (required)
  std::optional<std::filesystem::path> firetimes;  // optional firing-time CSV
  AssemblerOptions assembler;                      // assembler.model is the sensor model
  // Capacity of the stream, from the model: returns × firings per revolution at the lowest rpm.
  unsigned returns = 2;
  unsigned min_rpm = 600;
  bool checksum = false;
  bool lock_memory = false;
  std::chrono::milliseconds heartbeat_period{0};
  // The sensor's description (frame, mounting, identity, time base); the stream adds what it
  // knows: per-point times after the frame's stamp, vendor "Hesai" and the model when the
  // identity has none, and the calibration file as the calibration source when none is given.
  // nullopt: the stream carries no description.
  std::optional<SensorInfo> sensor;
};

// What the stream published, beside the assembler's own counters: frames, points,
// partial_frames (did not start at the cut azimuth) and failed commits.
using PublishCounters = lidar::PublishCounters;

class LidarStream {
 public:
  // Loads the calibration (and firing times), checks them against the model, and creates the
  // SIM stream sized for the model. Every failure is one sentence naming the file or stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config);

  LidarStream(LidarStream&&) noexcept;
  LidarStream& operator=(LidarStream&&) noexcept;
  LidarStream(const LidarStream&) = delete;
  LidarStream& operator=(const LidarStream&) = delete;
  ~LidarStream();

  // Decodes one UDP payload; publishes the revolution it completes, if any (returned).
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept;
  // End of input: publishes the revolution in progress when partial frames are enabled.
  std::optional<CompletedFrame> finish() noexcept;
  // Forgets the revolution in progress (a capture loops, a sensor was silent).
  void reset() noexcept;
  // Added to every published stamp from now on: a replay keeps stamps increasing across loops
  // of its capture, or moves them to the present (--restamp). Zero (the default) publishes the
  // sensor's own time, as the live driver does.
  void set_stamp_offset(std::int64_t offset_ns) noexcept;
  std::int64_t stamp_offset() const noexcept;

  Model model() const noexcept;
  const AssemblerCounters& counters() const noexcept;
  const PublishCounters& published() const noexcept;
  std::uint64_t max_points() const noexcept;
  // FrameAssembler::time_to_cut_ns: how long no packet can complete a revolution.
  std::optional<std::int64_t> time_to_cut_ns() const noexcept;
  Writer& writer() noexcept;
  // The clock check: the caller adds each packet's sensor time (PushResult::packet_ns) with its
  // arrival (live: the datagram's receive stamp; a replay: the record's capture time) and
  // ticks it; it judges and writes the stream's clock about once a second (`at_once`: now).
  timing::ClockReporter& clock() noexcept;
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false);

  // "frames 12 packets 3600 lost 0 malformed 0 wrong-model 0 points/frame 93591", for status
  // lines; `key=value` pairs with `machine` ("frames=12 packets=3600 …") for summaries.
  std::string describe_counters(bool machine = false) const;

  struct Impl;

 private:
  explicit LidarStream(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// Number of returns announced by a payload of `model` (1–3), or nullopt when it is not one.
std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept;

}  // namespace sim::hesai
