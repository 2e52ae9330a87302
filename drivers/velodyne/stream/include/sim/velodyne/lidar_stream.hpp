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
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "sim/clock_status.hpp"
#include "sim/lidar/frame_publisher.hpp"
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

class LidarStream {
 public:
  // Loads the calibration, checks it against the model, creates the SIM stream sized for the
  // model. Every failure is one sentence naming the file or stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config);

  LidarStream(LidarStream&&) noexcept;
  LidarStream& operator=(LidarStream&&) noexcept;
  LidarStream(const LidarStream&) = delete;
  LidarStream& operator=(const LidarStream&) = delete;
  ~LidarStream();

  // One data packet (port 2368). `time_reference_ns` picks the hour of the packet's timestamp
  // (0: host_receive_ns; a replay passes the capture's time).
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns,
                  std::int64_t time_reference_ns = 0) noexcept;
  // One position packet (port 8308) that arrived at `host_receive_ns` (CLOCK_REALTIME; 0: now):
  // updates the time sync, and the stream's description when it changed (as
  // LidarStreamConfig::stamp_clock says), and the reported clock. False when the payload is no
  // position packet (counted).
  bool push_position(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns = 0) noexcept;
  std::optional<CompletedFrame> finish() noexcept;
  void reset() noexcept;
  void set_stamp_offset(std::int64_t offset_ns) noexcept;
  std::int64_t stamp_offset() const noexcept;

  Model model() const noexcept;
  const AssemblerCounters& counters() const noexcept;
  const PublishCounters& published() const noexcept;
  const TimeSync& time_sync() const noexcept;
  // What the position packets last said of the sensor's clock, readable from any thread (see
  // ReportedClock). Before the first one: source unknown, reported_ns 0. A replay with the
  // recorded stamps reports source replayed with the recorded state; a restamped one, source host
  // (its stamps are this host's arrival times).
  ReportedClock reported_clock() const;
  Writer& writer() noexcept;
  // The clock check: the caller adds each packet's sensor time (PushResult::packet_ns) with its
  // arrival (live: the datagram's receive stamp; a replay: the record's capture time) and
  // ticks it; it judges and writes the stream's clock about once a second (`at_once`: now).
  timing::ClockReporter& clock() noexcept;
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false);
  // "frames 12 packets 9000 lost 0 malformed 0 wrong-model 0 points/frame 28800 time PPS locked…"
  // for status lines; key=value pairs with `machine` for summaries.
  std::string describe_counters(bool machine = false) const;

  struct Impl;

 private:
  explicit LidarStream(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// Returns announced by a data packet of `model` (1 or 2), or nullopt when it is not one.
std::optional<unsigned> returns_in(std::span<const std::uint8_t> payload, Model model) noexcept;

}  // namespace sim::velodyne
