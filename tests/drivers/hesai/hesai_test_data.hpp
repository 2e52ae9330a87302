// SPDX-License-Identifier: Apache-2.0
// Test-only: the Hesai recordings (data/, see data/NOTICE.md), read with the LiDAR test support
// every family shares (tests/support/lidar_test).
#pragma once

#include <filesystem>
#include <string>

#include "lidar_test/pcap_payloads.hpp"
#include "lidar_test/pcd.hpp"

namespace hesai_test {

using lidar_test::read_text;
using lidar_test::read_udp_payloads;
using lidar_test::UdpPayload;

// A file of tests/drivers/hesai/data (the HESAI_TEST_DATA compile definition).
inline std::filesystem::path data_path(const std::string& name) {
  return std::filesystem::path(HESAI_TEST_DATA) / name;
}

}  // namespace hesai_test
