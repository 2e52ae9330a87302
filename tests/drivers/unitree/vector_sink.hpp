// SPDX-License-Identifier: Apache-2.0
// A ScanSink over plain memory for the library tests: lends one fixed buffer per scan, like the
// SIM writer's loaned slot, and keeps copies of the finished scans and IMU samples.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <utility>

#include "sim/unitree/decoder.hpp"

namespace unitree_test {

struct Scan {
  std::vector<sim::LidarPoint> points;
  std::int64_t stamp_ns = 0;
  std::int64_t receive_ns = 0;
};

class VectorSink : public sim::unitree::ScanSink {
 public:
  explicit VectorSink(std::size_t capacity) : storage_(capacity) {}
  std::span<sim::LidarPoint> begin_scan() override {
    ++begun;
    return storage_;
  }
  void end_scan(std::size_t points, std::int64_t stamp_ns, std::int64_t receive_ns) override {
    scans.push_back({{storage_.begin(), storage_.begin() + static_cast<std::ptrdiff_t>(points)},
                     stamp_ns, receive_ns});
  }
  void imu(const sim::unitree::ImuSample& sample) override { imu_samples.push_back(sample); }
  void packet_time(std::int64_t stamp_ns, std::int64_t host_ns) override {
    packet_times.emplace_back(stamp_ns, host_ns);
  }

  std::vector<Scan> scans;
  std::vector<std::pair<std::int64_t, std::int64_t>> packet_times;  // (stamp, host) per packet
  std::vector<sim::unitree::ImuSample> imu_samples;
  int begun = 0;

 private:
  std::vector<sim::LidarPoint> storage_;
};

}  // namespace unitree_test
