// SPDX-License-Identifier: Apache-2.0
// LidarStream: the one path from an Ouster sensor's packets to SIM streams, shared by the live
// driver (sim_lidar_ouster) and the capture replay (sim_replay_pcap). It owns the point writer
// and the FrameAssembler (points are decoded straight into the writer's loaned slot) and, on its
// own stream, the IMU writer. No allocation per packet.
#pragma once

#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "sim/lidar/point_stream.hpp"
#include "sim/ouster/ouster.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/writer.hpp"

namespace sim::ouster {

// One IMU packet as published on the IMU stream (one SIM frame per packet, raw layout), in the
// IMU's frame (the metadata's imu_to_sensor_transform relates it to the sensor frame), SI units.
struct ImuSample {
  std::int64_t stamp_ns = 0;        // accelerometer read time, sensor clock
  std::int64_t gyro_stamp_ns = 0;   // gyroscope read time, sensor clock
  float linear_acceleration[3] = {0, 0, 0};  // m/s²
  float angular_velocity[3] = {0, 0, 0};     // rad/s
};
static_assert(sizeof(ImuSample) == 40, "ImuSample is the IMU stream's frame layout");

ImuSample to_sample(const ImuPacket& packet) noexcept;

// "/lidar_top" -> "/lidar_top.imu".
std::string default_imu_stream(const std::string& points_stream);

// A live sensor's clock for the stream's description (time_base, time_sync), from the metadata's
// timestamp_mode: TIME_FROM_INTERNAL_OSC is the sensor's own clock from power-on;
// TIME_FROM_PTP_1588 and TIME_FROM_SYNC_PULSE_IN synchronise it (whether it is locked is not
// read); without one, or with another, the time base is unknown and the sentence says why.
void describe_live_clock(SensorInfo& info, const Metadata& metadata);

struct LidarStreamConfig {
  std::string stream = "/lidar_top";
  std::string imu_stream;  // empty: no IMU stream
  AssemblerOptions assembler;
  // The stream's description (frame, mounting; see apps/common sensor_options.hpp); the stream
  // adds the identity, the calibration source and the point time. nullopt: none.
  std::optional<SensorInfo> sensor;
  std::string metadata_source;  // "file:///…/os1.json", "sensor http://…"
  bool checksum = false;
  bool lock_memory = false;
  std::chrono::milliseconds heartbeat_period{0};
};

// frames, points (organised: with and without a return), partial_frames (did not start at the
// window's first column), failed (commits the writer refused), and the IMU samples.
struct PublishCounters : lidar::PublishCounters {
  std::uint64_t imu_samples = 0;
  std::uint64_t imu_malformed = 0;   // IMU datagrams that were not 48-byte IMU packets
};

class LidarStream;

// What an Ouster stream is made of (see lidar::PointStream).
struct StreamFamily {
  using Assembler = FrameAssembler;
  using Counters = PublishCounters;
  struct State {
    std::optional<Writer> imu;  // its own stream, one frame per IMU packet
  };
  static constexpr bool whole_at_finish = true;  // the column window may be complete at the end
  // " imu 1200 points/frame 32768 …".
  static void describe(std::ostream& out, bool machine, const lidar::StreamPipeline<StreamFamily>& p);
};

// The common verbs (push, finish, reset, set_stamp_offset, counters, published, writer, clock,
// tick_clock, describe_counters: lidar::PointStream), the IMU packets and the metadata.
class LidarStream : public lidar::PointStream<StreamFamily> {
 public:
  // Creates the SIM streams sized for the metadata (H × W × returns points). Every failure is
  // one sentence naming the stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config, const Metadata& metadata);

  // One IMU payload; true when it was a sample (published when the IMU stream exists).
  bool push_imu(std::span<const std::uint8_t> payload) noexcept;

  const Metadata& metadata() const noexcept { return pipeline().assembler.metadata(); }
  // One sentence when lidar packets did not fit the metadata (beam count, columns, profile,
  // another sensor), for the user; empty while none did.
  std::string mismatch_problem() const;

 private:
  explicit LidarStream(std::unique_ptr<Pipeline> pipeline) noexcept : PointStream(std::move(pipeline)) {}
};

}  // namespace sim::ouster
