// SPDX-License-Identifier: Apache-2.0
// Test-only: the UDP payloads of a capture, read with libpcap (classic pcap and pcapng) and
// parsed Ethernet (+802.1Q) / IPv4 / UDP. The project's real reader is replay/pcap; this one
// exists so the decoder tests do not depend on it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hesai_test {

struct UdpPayload {
  std::int64_t capture_ns;  // capture timestamp (host receive time)
  std::uint16_t dst_port;
  std::vector<std::uint8_t> bytes;
};

// Throws std::runtime_error with libpcap's message when the file cannot be read.
std::vector<UdpPayload> read_udp_payloads(const std::filesystem::path& path);

// Test data folder (tests/drivers/hesai/data), from the HESAI_TEST_DATA compile definition.
std::filesystem::path data_path(const std::string& name);

// Whole file as bytes / text.
std::string read_text(const std::filesystem::path& path);

struct Xyz {
  float x, y, z;
};
// A binary PCD with x y z float fields only (nebula's reference clouds).
std::vector<Xyz> read_xyz_pcd(const std::filesystem::path& path);

}  // namespace hesai_test
