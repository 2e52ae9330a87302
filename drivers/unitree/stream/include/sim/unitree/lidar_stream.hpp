// SPDX-License-Identifier: Apache-2.0
// LidarStream: the one path from a Unitree L1's or L2's bytes to SIM streams, shared by the live
// driver (sim_lidar_unitree) and the replays (sim_replay_serial, sim_replay_pcap), so a consumer
// cannot tell them apart. It owns the point writer (lidar::FramePublisher: the Decoder writes
// each scan straight into the writer's loaned slot), the IMU writer and the clock check. No
// allocation per packet.
//
//   auto stream = sim::unitree::LidarStream::create(config);   // Expected<LidarStream>
//   stream->push(payload, host_receive_ns);   // any chunk: a UDP payload, a serial read
//   stream->tick_clock(now);                  // about once a second it writes the clock record
//   stream->finish();  stream->describe_counters(true);
//
// Unlike the Hesai, Velodyne and Ouster streams, which take one packet per push and return the
// frame it completes, a Unitree chunk is any cut of a byte stream: it may hold several packets,
// complete several scans (a serial read, --scan-packets 1, 2D-mode packets) and carry IMU
// samples. So the Decoder hands each scan to the stream as it completes it, and adds each
// packet's time to clock() itself; push() says how many frames the chunk published.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar/frame_publisher.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/writer.hpp"

namespace sim::unitree {

struct LidarStreamConfig {
  std::string stream = "/lidar_top";
  std::string imu_stream;  // empty: no IMU stream (default_imu_stream(stream) is the usual one)
  DecoderOptions decoder;  // the model, packets per scan, stamps, range limits
  bool checksum = false;
  bool lock_memory = false;
  std::chrono::milliseconds heartbeat_period{0};
  // The sensor's description (frame, parent, mounting); the stream completes it with
  // describe_sensor(). The IMU stream carries the same, without per-point times. nullopt: none.
  std::optional<SensorInfo> sensor;
  // How the L2's own stamps are judged (TimeSource::sensor): live sensor, a replay's replayed or
  // restamped. Host stamps are judged as host time whatever this says (stream_clock_base()).
  timing::ClockBase sensor_clock_base = timing::ClockBase::sensor;
  // Asked before each scan is committed, by a replay whose recording has no times of its own
  // (sim_replay_serial waits for the scan's turn here): the stamp to publish the scan with, or
  // nullopt to drop it (the replay is stopping). Empty: every scan is published at once with its
  // own stamp. Called once per scan, never per packet.
  std::function<std::optional<std::int64_t>()> publish_gate;
};

// frames, points, partial_frames (always 0: a scan is published only when whole), failed
// commits, and the IMU samples.
struct PublishCounters : lidar::PublishCounters {
  std::uint64_t imu_samples = 0;  // IMU samples written to the IMU stream
  std::uint64_t imu_failed = 0;   // IMU writes the writer refused
};

// "/lidar_top" → "/lidar_top.imu" (SIM names allow no second slash).
std::string default_imu_stream(std::string_view points_stream);

// How a stream's stamps are judged: `sensor_base` when they are the L2's own clock, otherwise
// host time (ClockBase::restamped: source host, stamps host_arrival); the L1 sends no time, so
// its stamps are always the host's.
timing::ClockBase stream_clock_base(const DecoderOptions& options, timing::ClockBase sensor_base) noexcept;

// `configured` (frame, parent, mounting from the command line) completed with what the decoder
// knows: vendor Unitree and the model, per-point times after the scan's stamp, and the clock of
// the stamps (the host's, or with TimeSource::sensor the L2's own, whose synchronisation the
// packets do not report), said in words in time_sync unless the caller set that already.
SensorInfo describe_sensor(SensorInfo configured, const DecoderOptions& options);

class LidarStream {
 public:
  // Creates the point stream, sized for the largest scan the decoder options make, and the IMU
  // stream when named. Every failure is one sentence naming the stream.
  static Expected<LidarStream> create(const LidarStreamConfig& config);

  LidarStream(LidarStream&&) noexcept;
  LidarStream& operator=(LidarStream&&) noexcept;
  LidarStream(const LidarStream&) = delete;
  LidarStream& operator=(const LidarStream&) = delete;
  ~LidarStream();

  // Any chunk of the sensor's byte stream with the host time it arrived (CLOCK_REALTIME live; a
  // replay's capture or read time): decodes it, publishes the scans it completes and writes its
  // IMU samples. Returns how many frames it published.
  std::size_t push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept;
  // End of input: a partial packet is counted as truncated; an unfinished scan is never
  // published (it is not a whole scan), so nothing is returned.
  void finish() noexcept;
  // Forgets the scan in progress and the buffered bytes (a replay loops back to its start);
  // counters are kept. The clock check is the caller's (clock().restart()), as for every family.
  void reset() noexcept;
  // Added to the L2's own stamps (TimeSource::sensor) from now on, frames and IMU samples alike:
  // a replay's loops and --restamp. Host stamps are given with the bytes and never moved here.
  void set_stamp_offset(std::int64_t offset_ns) noexcept;
  std::int64_t stamp_offset() const noexcept;

  Model model() const noexcept;
  const DecoderOptions& options() const noexcept;
  DecoderCounters counters() const noexcept;
  const PublishCounters& published() const noexcept;
  std::uint64_t max_points() const noexcept;
  Writer& writer() noexcept;
  // The clock check: every packet that carries a time is added by the stream itself, with the
  // host time of its chunk; tick_clock judges about once a second (`at_once`: now) and writes
  // the record to the point stream and the IMU stream (the same clock).
  timing::ClockReporter& clock() noexcept;
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false);

  // "frames 12 packets 216 lost 0 malformed 0 imu 250 points/frame 5400", and the problems seen
  // ("bad-crc 3"), for status lines; `key=value` pairs with `machine` ("frames=12 packets=216 …
  // imu=250 failed=0 …") for summaries.
  std::string describe_counters(bool machine = false) const;

  struct Impl;

 private:
  explicit LidarStream(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::unitree
