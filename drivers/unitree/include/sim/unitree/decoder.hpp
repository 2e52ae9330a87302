// SPDX-License-Identifier: Apache-2.0
// The one decoding path of every Unitree tool: live UDP, live serial, serial replay and pcap
// replay all push raw bytes into a Decoder, which frames them (L2 packets or L1 MAVLink),
// checks them, converts points with the SDK's formulas and assembles scans straight into the
// storage a ScanSink lends it (for SIM, the writer's loaned slot). No I/O, no allocation after
// construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sim/lidar_point.hpp"
#include "sim/unitree/framing.hpp"
#include "sim/unitree/imu.hpp"
#include "sim/unitree/l1_protocol.hpp"

namespace sim::unitree {

enum class Model { l1, l2 };
const char* to_string(Model model) noexcept;
// Accepts "L1", "L2" (any case) and the pcap tool's "unitree-l1" / "unitree-l2".
std::optional<Model> parse_model(std::string_view text) noexcept;
// Empty when parse_model accepts `text`; otherwise one sentence naming the models.
std::string model_problem(std::string_view text);

// Where decoded data goes. The decoder calls begin_scan() at the first packet of a scan, writes
// points into the span it returns, and calls end_scan() when the scan is complete.
class ScanSink {
 public:
  virtual ~ScanSink() = default;
  virtual std::span<LidarPoint> begin_scan() = 0;
  // receive_ns: host receive time (CLOCK_REALTIME) of the scan's first packet.
  virtual void end_scan(std::size_t points, std::int64_t stamp_ns, std::int64_t receive_ns) = 0;
  virtual void imu(const ImuSample& sample) = 0;
  // Every packet that carries a time (L2 points, 2D points and IMU; L1 point pairs and IMU): the
  // time it is stamped with (the L2's own clock with TimeSource::sensor, else `host_ns`) and the
  // host time its bytes arrived with. For the stream's clock check; ignored by default.
  virtual void packet_time(std::int64_t stamp_ns, std::int64_t host_ns) {
    static_cast<void>(stamp_ns);
    static_cast<void>(host_ns);
  }
};

enum class TimeSource {
  host,    // the host time given with the bytes (receive time live, capture time in replay)
  sensor,  // the L2's own packet stamps (only meaningful once the lidar's clock is synced)
};

struct DecoderOptions {
  Model model = Model::l2;
  // Packets per published scan: the SDKs' cloud_scan_num (18 ≈ 10 Hz clouds).
  std::uint32_t packets_per_scan = 18;
  TimeSource time_source = TimeSource::host;
  float range_min_m = 0.0F;
  float range_max_m = 1.0e9F;
};

struct DecoderCounters {
  FramerCounters framing;
  std::uint64_t scans = 0;           // scans handed to end_scan
  std::uint64_t points = 0;          // points written into scans
  std::uint64_t dropped_points = 0;  // points that did not fit the sink's storage
  std::uint64_t lost_packets = 0;    // L2 sequence gaps
  std::uint64_t imu_samples = 0;
  std::uint64_t unpaired = 0;        // L1 distance/auxiliary packets without their partner
  std::uint64_t ignored = 0;         // good packets of types not decoded (version, ACK…)
  std::uint64_t malformed = 0;       // good CRC but impossible contents (too many points)
};

// Opens a scan at its first packet and hands it to the sink after packets_per_scan packets.
class ScanAssembler {
 public:
  ScanAssembler(ScanSink& sink, std::uint32_t packets_per_scan) noexcept;
  // Room for one packet's points (empty when the scan's storage is full).
  std::span<LidarPoint> begin_packet(std::int64_t stamp_ns, std::int64_t clock_ns,
                                     std::int64_t receive_ns) noexcept;
  // `clock_ns` of the scan's first packet, on the clock used for time offsets.
  std::int64_t scan_clock_ns() const noexcept { return scan_clock_ns_; }
  // Returns whether this packet completed (and published) the scan.
  bool end_packet(std::size_t points_written) noexcept;
  std::uint32_t packets_in_scan() const noexcept { return open_ ? packets_ : 0; }
  // Drops the open scan unpublished (its storage is simply not committed).
  void abandon() noexcept;
  // Publishes the open scan now, whatever its packet count (a 2D packet is a whole scan).
  void close() noexcept;

 private:
  ScanSink& sink_;
  std::uint32_t packets_per_scan_;
  std::span<LidarPoint> storage_{};
  bool open_ = false;
  std::size_t points_ = 0;
  std::uint32_t packets_ = 0;
  std::int64_t stamp_ns_ = 0;
  std::int64_t receive_ns_ = 0;
  std::int64_t scan_clock_ns_ = 0;
};

class Decoder {
 public:
  Decoder(const DecoderOptions& options, ScanSink& sink);

  // Points in the largest scan these options produce: size the sink's storage with it.
  // (For the L2 at least one 2D-mode packet, 1,800 points, which is published as one scan.)
  static std::uint64_t max_points_per_scan(const DecoderOptions& options) noexcept;

  // Any chunk of the byte stream: one UDP datagram (holding several packets or part of one), or
  // whatever a serial read returned. host_ns is the host time the bytes arrived (CLOCK_REALTIME).
  void push(std::span<const std::uint8_t> bytes, std::int64_t host_ns) noexcept;
  // End of input: a partial packet is counted as truncated; an unfinished scan is not published.
  void finish() noexcept;
  // Starts over on a new, unrelated byte stream (a replay looping back to its start): buffered
  // bytes and the open scan are dropped, counters are kept.
  void reset() noexcept;

  DecoderCounters counters() const noexcept;
  const DecoderOptions& options() const noexcept { return options_; }

  // Added to the L2's own stamps (TimeSource::sensor): a replay moves them on by each --loop, or
  // to the present with --restamp. Host stamps are given with the bytes and never moved here.
  void set_stamp_offset(std::int64_t offset_ns) noexcept { stamp_offset_ns_ = offset_ns; }
  std::int64_t stamp_offset() const noexcept { return stamp_offset_ns_; }

 private:
  void drain(std::int64_t host_ns) noexcept;
  void on_l2_packet(std::span<const std::uint8_t> packet, std::int64_t host_ns) noexcept;
  void on_l2_2d_packet(std::span<const std::uint8_t> packet, std::int64_t host_ns) noexcept;
  void on_l1_message(const MavlinkMessage& message, std::int64_t host_ns) noexcept;
  void decode_l1_pair(std::int64_t host_ns) noexcept;
  // The stamp of a packet with the sensor time `sensor_ns`, as TimeSource says.
  std::int64_t stamp_of(std::int64_t sensor_ns, std::int64_t host_ns) const noexcept;

  DecoderOptions options_;
  ScanSink& sink_;
  ScanAssembler assembler_;
  L2Framer l2_framer_;
  MavlinkFramer l1_framer_;
  DecoderCounters counters_;
  std::int64_t stamp_offset_ns_ = 0;
  std::optional<std::uint32_t> last_seq_;
  std::optional<l1::DistancePacket> l1_distance_;
  std::optional<l1::AuxiliaryPacket> l1_aux_;
};

}  // namespace sim::unitree
