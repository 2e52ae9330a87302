// SPDX-License-Identifier: Apache-2.0
// Test-only: the UDP payloads of a capture, read with libpcap (classic pcap and pcapng) and
// parsed Ethernet (+802.1Q) / IPv4 / UDP. The project's real reader is replay/pcap; this one
// exists so the decoder tests of every family do not depend on it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace lidar_test {

struct UdpPayload {
  std::int64_t capture_ns;  // capture timestamp (host receive time)
  std::uint16_t dst_port;
  std::vector<std::uint8_t> bytes;
};

// Throws std::runtime_error with libpcap's message when the file cannot be read.
std::vector<UdpPayload> read_udp_payloads(const std::filesystem::path& path);

// Whole file as bytes / text; throws std::runtime_error when it cannot be opened.
std::string read_text(const std::filesystem::path& path);

}  // namespace lidar_test
