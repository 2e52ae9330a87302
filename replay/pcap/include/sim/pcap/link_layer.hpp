// SPDX-License-Identifier: Apache-2.0
// Finds the UDP datagram inside one captured link-layer frame, by parsing every header on the
// way (Ethernet with 802.1Q/802.1ad tags, Linux cooked SLL and SLL2, raw IP, BSD loopback;
// IPv4 with options, IPv6 with extension headers). Nothing here assumes the classic 42-byte
// Ethernet+IPv4+UDP offset: captures from a VLAN trunk, from "tcpdump -i any" or from a
// tunnel put the payload elsewhere. Pure function of its input, so it is fuzzed directly.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace sim::pcap {

// A link-layer header type as libpcap numbers it (DLT_*): the value of pcap_datalink().
struct LinkType {
  int dlt = -1;
  friend bool operator==(LinkType, LinkType) = default;
};

// Whether parse_frame() understands frames of this link type.
bool is_supported(LinkType link) noexcept;
// "EN10MB (Ethernet)", or "DLT 147" when libpcap has no name for it.
std::string describe(LinkType link);
// The list of supported link types, for error messages.
std::string supported_link_types();

// An IPv4 or IPv6 address and a UDP port.
struct Endpoint {
  std::array<std::uint8_t, 16> address{};  // IPv4 uses the first 4 bytes
  std::uint8_t ip_version = 0;             // 4 or 6
  std::uint16_t port = 0;

  // "192.168.1.201:10000" or "[fe80::1]:2368".
  std::string to_string() const;
  friend bool operator==(const Endpoint&, const Endpoint&) = default;
};

// One UDP datagram found in a frame. The payload points into the caller's frame bytes.
struct Datagram {
  std::int64_t timestamp_ns = 0;  // capture time (CLOCK_REALTIME of the capturing host)
  Endpoint source;
  Endpoint destination;
  std::span<const std::byte> payload;
};

// Why a frame holds no usable datagram. Each is counted by the capture reader, never fatal:
// real captures mix ARP, ICMP, TCP and LiDAR traffic.
enum class FrameStatus : std::uint8_t {
  ok,
  not_ip,         // ARP, LLDP, … : not IPv4 or IPv6
  not_udp,        // IP, but TCP, ICMP, …
  fragment,       // an IP fragment: IPv4 UDP ones are reassembled by the capture reader
  truncated,      // the frame ends before its own headers say it does (snaplen or a cut file)
  malformed,      // header fields that cannot be (IHL < 5, UDP length < 8, version ≠ 4/6, …)
  unsupported_link,
};

const char* to_string(FrameStatus status) noexcept;

// One IPv4 fragment of a UDP datagram, for reassembly (the capture reader's ip_reassembly).
struct Ipv4Fragment {
  std::array<std::uint8_t, 4> source{};
  std::array<std::uint8_t, 4> destination{};
  std::uint16_t id = 0;
  std::uint8_t protocol = 0;
  std::uint32_t offset = 0;  // bytes (the header's 13-bit field × 8)
  bool more = false;         // MF flag
  std::span<const std::byte> data;  // the fragment's part of the IP payload
};

// Parses one frame of the given link type. On ok, `out.source`, `out.destination` and
// `out.payload` are set (the payload as long as the UDP length field says, which the frame is
// checked to hold); `out.timestamp_ns` is left alone. On fragment (IPv4 UDP), `fragment`, when
// given, receives its identification, offset and bytes for reassembly.
FrameStatus parse_frame(LinkType link, std::span<const std::byte> frame, Datagram& out,
                        Ipv4Fragment* fragment = nullptr) noexcept;

// The UDP datagram in a reassembled IPv4 payload whose fragments came from `first`'s endpoints.
FrameStatus parse_reassembled(const Ipv4Fragment& first, std::span<const std::byte> ip_payload,
                              Datagram& out) noexcept;

}  // namespace sim::pcap
