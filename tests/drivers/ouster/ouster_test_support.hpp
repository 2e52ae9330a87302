// SPDX-License-Identifier: Apache-2.0
// Test-only: the recorded captures (data/) as payloads and their metadata.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lidar_test/pcap_payloads.hpp"
#include "sim/ouster/metadata.hpp"

namespace ouster_test {

inline std::filesystem::path data_path(const std::string& name) {
  return std::filesystem::path(OUSTER_TEST_DATA) / name;
}
using lidar_test::read_text;

struct Capture {
  sim::ouster::Metadata metadata;
  std::vector<std::vector<std::uint8_t>> lidar;  // port 7502, in capture order
  std::vector<std::vector<std::uint8_t>> imu;    // port 7503
};

// "OS-1-32-G_v2.1.1_1024x10": its .pcap and .json.
inline Capture load_capture(const std::string& base) {
  Capture c;
  auto metadata = sim::ouster::Metadata::load(data_path(base + ".json"));
  if (!metadata) throw std::runtime_error(metadata.error().message);
  c.metadata = std::move(metadata.value());
  for (auto& p : lidar_test::read_udp_payloads(data_path(base + ".pcap"))) {
    if (p.dst_port == 7502) c.lidar.push_back(std::move(p.bytes));
    if (p.dst_port == 7503) c.imu.push_back(std::move(p.bytes));
  }
  return c;
}

}  // namespace ouster_test
