// SPDX-License-Identifier: Apache-2.0
// The SIM end of every Unitree tool (live driver, serial replay, pcap replay): a ScanSink that
// lends the decoder the point stream's back slot (writer.loan()) for each scan and commits it
// when the scan is complete, and writes IMU samples to their own small stream.
//
// The pcap replay uses it like this:
//   auto sink = sim::unitree::SimScanSink::create({.points_stream = "/lidar_top", …});
//   sim::unitree::Decoder decoder(options, **sink);
//   for each UDP payload: decoder.push(payload, capture_time_ns);
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "sim/result.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/writer.hpp"

namespace sim::unitree {

struct SimSinkOptions {
  std::string points_stream;  // "/lidar_top"
  std::string imu_stream;     // "/lidar_top.imu"; empty: IMU samples are dropped
  std::uint64_t max_points = 0;  // Decoder::max_points_per_scan(options)
  bool checksum = false;
};

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
  void end_scan(std::size_t points, std::int64_t stamp_ns) override;
  void imu(const ImuSample& sample) override;

  const SimSinkCounters& counters() const noexcept { return counters_; }
  const Writer& points_writer() const noexcept { return points_; }

 private:
  SimScanSink(Writer points, std::optional<Writer> imu, std::uint64_t max_points) noexcept;
  Writer points_;
  std::optional<Writer> imu_;
  std::uint64_t max_points_;
  std::optional<Loan> loan_;
  SimSinkCounters counters_;
};

// One status line: "scans 12 points 64800 imu 250 | bad_crc 0 truncated 0 resyncs 0 …".
std::string format_status(const DecoderCounters& decoder, const SimSinkCounters& sink);

}  // namespace sim::unitree
