// SPDX-License-Identifier: Apache-2.0
// LidarStream: the one path from Velodyne UDP payloads to a SIM stream, shared by the live
// driver (sim_lidar_velodyne) and the capture replay (sim_replay_pcap), so a consumer cannot
// tell them apart. It owns the SIM writer and the FrameAssembler, keeps the assembler's output
// pointed at the writer's loaned slot, commits each revolution with the sensor time of its first
// point, and turns position packets (GPRMC, PPS) into the stream's time-sync description.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "sim/clock_status.hpp"
#include "sim/lidar/point_stream.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/timing/reported_clock.hpp"
#include "sim/velodyne/velodyne.hpp"
#include "sim/writer.hpp"

namespace sim::velodyne {

// Which clock the stamps are, and so what position packets (GPRMC, PPS) do to the description.
enum class StampClock {
  sensor_live,      // the sensor's, live: the reported state is the time base and time_sync
  sensor_recorded,  // the sensor's as recorded (a replay with the recorded stamps): the recorded
                    // state gives the time base and follows the caller's time_sync
                    // ("<sensor->time_sync>; as recorded: PPS locked, GPRMC valid")
  restamped,        // not the sensor's (a replay restamped to this host's clock): the caller's
                    // time base and time_sync stand; position packets only reach the counters
                    // and status lines
};

struct LidarStreamConfig {
  std::string stream = "/lidar_top";
  std::filesystem::path calibration;  // YAML or db.xml (required)
  AssemblerOptions assembler;         // assembler.model is the sensor model
  unsigned returns = 2;               // capacity: returns × packets of a revolution at min_rpm
  unsigned min_rpm = 300;
  // The stream's description (frame, mounting; apps/common sensor_options.hpp); the stream adds
  // the identity, the calibration source, the point time and the time sync (as stamp_clock says).
  // nullopt: none.
  std::optional<SensorInfo> sensor;
  StampClock stamp_clock = StampClock::sensor_live;
  bool checksum = false;
  bool lock_memory = false;
  std::chrono::milliseconds heartbeat_period{0};
};

// frames, points, partial_frames, failed (commits the writer refused), and position packets.
struct PublishCounters : lidar::PublishCounters {
  std::uint64_t position_packets = 0;  // GPRMC/PPS reports taken
  std::uint64_t position_malformed = 0;
};

// The clock state position packets report, in words for SensorInfo::time_sync and status lines:
// "PPS locked, GPRMC valid", "PPS absent, GPRMC no fix", "no position packet yet".
struct TimeSync {
  TimeBase base = TimeBase::unknown;
  std::string text = "no position packet yet";
};
TimeSync time_sync_of(const PositionReport& report);

// What the position packets last said of the sensor's clock, for the clock check on another thread.
using timing::ReportedClock;

class LidarStream;

// What a Velodyne stream is made of (see lidar::PointStream).
struct StreamFamily {
  using Assembler = FrameAssembler;
  using Counters = PublishCounters;
  // Beside the pipeline: what the position packets said, and how it reaches the description.
  struct State {
    std::optional<SensorInfo> sensor;  // the description, re-set when the time sync changes
    TimeSync sync;
    ReportedClock reported;  // what the position packets last said of the clock
    StampClock stamp_clock = StampClock::sensor_live;
    std::string caller_time_sync;  // LidarStreamConfig::sensor's, which sensor_recorded extends
  };
  static constexpr bool whole_at_finish = false;  // a revolution is whole when the next begins
  // " wrong-model 0 points/frame 28800 … time PPS locked, GPRMC valid".
  static void describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& p);
};

// The common verbs (push, finish, reset, set_stamp_offset, counters, published, writer, clock,
// tick_clock, describe_counters: lidar::PointStream), the model and the position packets.
// push(payload, host_receive_ns, time_reference_ns = 0): one data packet (port 2368);
// `time_reference_ns` picks the hour of the packet's timestamp (0: host_receive_ns; a replay
// passes the capture's time).
class LidarStream : public lidar::PointStream<StreamFamily> {
 public:
  // Loads the calibration, checks it against the model, creates the SIM stream sized for the
  // model. Every failure is one sentence naming the file or stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config);

  // One position packet (port 8308) that arrived at `host_receive_ns` (CLOCK_REALTIME; 0: now):
  // updates the time sync, and the stream's description when it changed (as
  // LidarStreamConfig::stamp_clock says), and the reported clock. False when the payload is no
  // position packet (counted).
  bool push_position(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns = 0) noexcept;

  Model model() const noexcept { return pipeline().assembler.options().model; }
  const TimeSync& time_sync() const noexcept { return pipeline().state.sync; }
  // What the position packets last said of the sensor's clock, readable from any thread (see
  // ReportedClock). Before the first one: source unknown, reported_ns 0. A replay with the
  // recorded stamps reports source replayed with the recorded state; a restamped one, source host
  // (its stamps are this host's arrival times).
  ReportedClock reported_clock() const { return pipeline().state.reported; }

 private:
  explicit LidarStream(std::unique_ptr<Pipeline> pipeline) noexcept : PointStream(std::move(pipeline)) {}
};

// Returns announced by a data packet of `model` (1 or 2), or nullopt when it is not one.
std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept;

}  // namespace sim::velodyne
