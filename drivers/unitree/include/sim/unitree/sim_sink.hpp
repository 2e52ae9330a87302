// SPDX-License-Identifier: Apache-2.0
// The SIM end of every Unitree tool (live driver, serial replay, pcap replay): a ScanSink that
// lends the decoder the point stream's back slot (writer.loan()) for each scan and commits it
// when the scan is complete, and writes IMU samples to their own small stream.
//
// UnitreeStream (below) bundles the decoder with this sink; the pcap replay uses it like this:
//   sim::unitree::UnitreeStreamOptions o;
//   o.decoder.model = sim::unitree::Model::l2;   // parse_model("unitree-l2")
//   o.points_stream = "/lidar_top";               // IMU goes to "/lidar_top.imu"
//   auto stream = sim::unitree::UnitreeStream::create(o);   // Expected<unique_ptr<…>>
//   for each UDP payload: (*stream)->push(payload, capture_time_ns);
//   (*stream)->finish(); then (*stream)->status() for the summary line.
//
// The clock record: every packet's stamp goes into a lidar::ClockReporter with the host time its
// bytes came with (Decoder::push), and tick_clock() writes the judgement to both streams about
// once a second. With TimeSource::sensor that measures the L2's own clock against the arrival
// (ClockBase sensor live, replayed or restamped in a replay); with host stamps the record says
// source host, stamps host_arrival (ClockBase::restamped: host time, judged as such).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "sim/lidar/clock_reporter.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/writer.hpp"

namespace sim::unitree {

struct SimSinkOptions {
  std::string points_stream;  // "/lidar_top"
  std::string imu_stream;     // "/lidar_top.imu"; empty: IMU samples are dropped
  std::uint64_t max_points = 0;  // Decoder::max_points_per_scan(options)
  bool checksum = false;
  // The description the point stream carries (describe_sensor() below); the IMU stream carries
  // the same frame and clock, without per-point times. nullopt: none.
  std::optional<SensorInfo> sensor;
  // How the stamps are judged (stream_clock_base() below).
  lidar::ClockBase clock_base = lidar::ClockBase::restamped;
};

// How a stream's stamps are judged: `sensor_base` (sensor live, replayed or restamped in a
// replay) when they are the L2's own clock, otherwise host time (ClockBase::restamped: source
// host, stamps host_arrival); the L1 sends no time, so its stamps are always the host's.
lidar::ClockBase stream_clock_base(const DecoderOptions& options, lidar::ClockBase sensor_base) noexcept;

// `configured` (frame, parent, mounting from the command line) completed with what the decoder
// knows: vendor Unitree and the model, per-point times after the scan's stamp, and the clock of
// the stamps (the host's, or with TimeSource::sensor the L2's own, whose synchronisation the
// packets do not report), said in words in time_sync unless the caller set that already.
SensorInfo describe_sensor(SensorInfo configured, const DecoderOptions& options);

// "/lidar_top" → "/lidar_top.imu" (SIM names allow no second slash).
std::string default_imu_stream(std::string_view points_stream);

struct SimSinkCounters {
  std::uint64_t scans_published = 0;
  std::uint64_t imu_published = 0;
  std::uint64_t publish_failures = 0;
};

class SimScanSink final : public ScanSink {
 public:
  static Expected<std::unique_ptr<SimScanSink>> create(const SimSinkOptions& options);

  std::span<LidarPoint> begin_scan() override;
  void end_scan(std::size_t points, std::int64_t stamp_ns, std::int64_t receive_ns) override;
  void imu(const ImuSample& sample) override;
  void packet_time(std::int64_t stamp_ns, std::int64_t host_ns) override {
    clock_.add(stamp_ns, host_ns);
  }

  // Judges the clock about once a second (lidar::ClockReporter::tick) and writes it to the
  // point stream and the IMU stream; `at_once`: now (the end of a replay).
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false);
  lidar::ClockReporter& clock() noexcept { return clock_; }

  const SimSinkCounters& counters() const noexcept { return counters_; }
  const Writer& points_writer() const noexcept { return points_; }

 private:
  SimScanSink(Writer points, std::optional<Writer> imu, std::uint64_t max_points) noexcept;
  lidar::ClockReporter clock_;
  Writer points_;
  std::optional<Writer> imu_;
  std::uint64_t max_points_;
  std::optional<Loan> loan_;
  SimSinkCounters counters_;
};

struct UnitreeStreamOptions {
  DecoderOptions decoder;
  std::string points_stream;
  // Empty: "<points_stream>.imu"; use `no_imu` to publish no IMU stream at all.
  std::string imu_stream;
  bool no_imu = false;
  bool checksum = false;
  std::optional<SensorInfo> sensor;  // completed by describe_sensor(); nullopt: none
  // How the L2's own stamps are judged (TimeSource::sensor): a replay says replayed or
  // restamped. Host stamps are judged as host time whatever this says (stream_clock_base()).
  lidar::ClockBase sensor_clock_base = lidar::ClockBase::sensor;
};

// The decoder writing into SIM: what the live driver and the pcap replay each run.
class UnitreeStream {
 public:
  static Expected<std::unique_ptr<UnitreeStream>> create(const UnitreeStreamOptions& options);

  // Any chunk of the sensor's byte stream (a UDP payload, a serial read), with its host time.
  void push(std::span<const std::byte> bytes, std::int64_t host_ns) noexcept {
    decoder_.push(bytes, host_ns);
  }
  void finish() noexcept { decoder_.finish(); }
  // A looping replay starts its file again: a new measurement of the clock too.
  void reset() noexcept {
    decoder_.reset();
    sink_->clock().restart();
  }
  // The L2's own stamps moved on (Decoder::set_stamp_offset): a replay's loops and --restamp.
  void set_stamp_offset(std::int64_t offset_ns) noexcept { decoder_.set_stamp_offset(offset_ns); }
  std::int64_t stamp_offset() const noexcept { return decoder_.stamp_offset(); }

  lidar::ClockReporter& clock() noexcept { return sink_->clock(); }
  std::optional<ClockStatus> tick_clock(std::int64_t now_realtime_ns, bool at_once = false) {
    return sink_->tick_clock(now_realtime_ns, at_once);
  }
  const DecoderOptions& decoder_options() const noexcept { return decoder_.options(); }

  DecoderCounters decoder_counters() const noexcept { return decoder_.counters(); }
  const SimSinkCounters& sink_counters() const noexcept { return sink_->counters(); }
  std::string status() const;

 private:
  UnitreeStream(std::unique_ptr<SimScanSink> sink, const DecoderOptions& options)
      : sink_(std::move(sink)), decoder_(options, *sink_) {}
  std::unique_ptr<SimScanSink> sink_;
  Decoder decoder_;
};

// One status line: "scans 12 points 64800 imu 250 | bad_crc 0 truncated 0 resyncs 0 …".
std::string format_status(const DecoderCounters& decoder, const SimSinkCounters& sink);

}  // namespace sim::unitree
