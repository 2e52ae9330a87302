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
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "sim/hesai/hesai.hpp"
#include "sim/lidar/point_stream.hpp"
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

class LidarStream;

// What a Hesai stream is made of (see lidar::PointStream).
struct StreamFamily {
  using Assembler = FrameAssembler;
  using Counters = PublishCounters;
  struct State {};
  static constexpr bool whole_at_finish = false;  // a revolution is whole when the next begins
  // " wrong-model 0 points/frame 93591 …" (the safety state of a QT128, the motor's rpm).
  static void describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& p);
};

// The common verbs (push, finish, reset, set_stamp_offset, counters, published, writer, clock,
// tick_clock, describe_counters: lidar::PointStream) and the Hesai model.
class LidarStream : public lidar::PointStream<StreamFamily> {
 public:
  // Loads the calibration (and firing times), checks them against the model, and creates the
  // SIM stream sized for the model. Every failure is one sentence naming the file or stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config);

  Model model() const noexcept { return pipeline().assembler.options().model; }
  // FrameAssembler::time_to_cut_ns: how long no packet can complete a revolution.
  std::optional<std::int64_t> time_to_cut_ns() const noexcept { return pipeline().assembler.time_to_cut_ns(); }

 private:
  explicit LidarStream(std::unique_ptr<Pipeline> pipeline) noexcept : PointStream(std::move(pipeline)) {}
};

// Number of returns announced by a payload of `model` (1–3), or nullopt when it is not one.
std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept;

}  // namespace sim::hesai
