// SPDX-License-Identifier: Apache-2.0
#include "sim/pcap/link_layer.hpp"

#include <arpa/inet.h>
#include <pcap/pcap.h>

#include <cstdio>

namespace sim::pcap {
namespace {

// libpcap maps a file's LINKTYPE_* to the platform's DLT_* values (LINKTYPE_RAW 101 becomes
// DLT_RAW, which is 12 on Linux and 14 on OpenBSD), so the platform macros are the right names.
constexpr int dlt_null = DLT_NULL;            // BSD loopback: 4-byte family, host byte order
constexpr int dlt_en10mb = DLT_EN10MB;        // Ethernet
constexpr int dlt_raw = DLT_RAW;              // raw IPv4 or IPv6
constexpr int dlt_loop = DLT_LOOP;            // OpenBSD loopback: family in network byte order
constexpr int dlt_linux_sll = DLT_LINUX_SLL;  // "tcpdump -i any" before libpcap 1.10
constexpr int dlt_ipv4 = DLT_IPV4;
constexpr int dlt_ipv6 = DLT_IPV6;
constexpr int dlt_linux_sll2 = DLT_LINUX_SLL2;  // "tcpdump -i any" since libpcap 1.10

constexpr std::uint16_t ethertype_ipv4 = 0x0800;
constexpr std::uint16_t ethertype_ipv6 = 0x86dd;
constexpr std::uint16_t ethertype_vlan = 0x8100;    // 802.1Q
constexpr std::uint16_t ethertype_qinq = 0x88a8;    // 802.1ad service tag
constexpr std::uint16_t ethertype_qinq_old = 0x9100;
constexpr int max_vlan_tags = 4;

constexpr std::uint8_t ip_proto_udp = 17;

// A bounds-checked cursor over the frame: every read states how many bytes it needs.
class Bytes {
 public:
  explicit Bytes(std::span<const std::byte> bytes) noexcept : bytes_(bytes) {}
  std::size_t size() const noexcept { return bytes_.size(); }
  bool has(std::size_t n) const noexcept { return bytes_.size() >= n; }
  std::uint8_t u8(std::size_t at) const noexcept { return std::to_integer<std::uint8_t>(bytes_[at]); }
  std::uint16_t be16(std::size_t at) const noexcept {
    return static_cast<std::uint16_t>((u8(at) << 8) | u8(at + 1));
  }
  std::uint32_t le32(std::size_t at) const noexcept {
    return std::uint32_t{u8(at)} | std::uint32_t{u8(at + 1)} << 8 | std::uint32_t{u8(at + 2)} << 16 |
           std::uint32_t{u8(at + 3)} << 24;
  }
  std::uint32_t be32(std::size_t at) const noexcept {
    return std::uint32_t{u8(at)} << 24 | std::uint32_t{u8(at + 1)} << 16 |
           std::uint32_t{u8(at + 2)} << 8 | std::uint32_t{u8(at + 3)};
  }
  Bytes after(std::size_t n) const noexcept { return Bytes(bytes_.subspan(n)); }
  Bytes first(std::size_t n) const noexcept { return Bytes(bytes_.first(n)); }
  std::span<const std::byte> span() const noexcept { return bytes_; }

 private:
  std::span<const std::byte> bytes_;
};

FrameStatus parse_udp(Bytes udp, Datagram& out) noexcept {
  if (!udp.has(8)) return FrameStatus::truncated;
  const std::uint16_t length = udp.be16(4);
  if (length < 8) return FrameStatus::malformed;
  if (!udp.has(length)) return FrameStatus::truncated;
  out.source.port = udp.be16(0);
  out.destination.port = udp.be16(2);
  out.payload = udp.span().subspan(8, length - 8u);
  return FrameStatus::ok;
}

FrameStatus parse_ipv4(Bytes ip, Datagram& out, Ipv4Fragment* fragment) noexcept {
  if (!ip.has(20)) return FrameStatus::truncated;
  if ((ip.u8(0) >> 4) != 4) return FrameStatus::malformed;
  const std::size_t header_length = std::size_t{ip.u8(0) & 0x0fu} * 4;  // IHL: options included
  const std::size_t total_length = ip.be16(2);
  if (header_length < 20 || total_length < header_length) return FrameStatus::malformed;
  // Ethernet pads short frames and some NICs append trailers: the IP length is the truth.
  if (!ip.has(total_length)) return FrameStatus::truncated;
  const std::uint16_t flags_fragment = ip.be16(6);
  const bool more_fragments = (flags_fragment & 0x2000u) != 0;
  const bool later_fragment = (flags_fragment & 0x1fffu) != 0;
  if (ip.u8(9) != ip_proto_udp) return FrameStatus::not_udp;
  if (more_fragments || later_fragment) {
    if (fragment != nullptr) {  // for the reassembler (ip_reassembly.hpp)
      for (std::size_t i = 0; i < 4; ++i) {
        fragment->source[i] = ip.u8(12 + i);
        fragment->destination[i] = ip.u8(16 + i);
      }
      fragment->id = ip.be16(4);
      fragment->protocol = ip.u8(9);
      fragment->offset = std::uint32_t{flags_fragment & 0x1fffu} * 8;
      fragment->more = more_fragments;
      fragment->data = ip.first(total_length).after(header_length).span();
    }
    return FrameStatus::fragment;
  }
  out.source = {};
  out.destination = {};
  out.source.ip_version = out.destination.ip_version = 4;
  for (std::size_t i = 0; i < 4; ++i) {
    out.source.address[i] = ip.u8(12 + i);
    out.destination.address[i] = ip.u8(16 + i);
  }
  return parse_udp(ip.first(total_length).after(header_length), out);
}

FrameStatus parse_ipv6(Bytes ip, Datagram& out) noexcept {
  if (!ip.has(40)) return FrameStatus::truncated;
  if ((ip.u8(0) >> 4) != 6) return FrameStatus::malformed;
  const std::size_t payload_length = ip.be16(4);  // 0 means a jumbogram: not a LiDAR packet
  if (payload_length == 0) return FrameStatus::malformed;
  if (!ip.has(40 + payload_length)) return FrameStatus::truncated;
  out.source = {};
  out.destination = {};
  out.source.ip_version = out.destination.ip_version = 6;
  for (std::size_t i = 0; i < 16; ++i) {
    out.source.address[i] = ip.u8(8 + i);
    out.destination.address[i] = ip.u8(24 + i);
  }
  std::uint8_t next = ip.u8(6);
  Bytes rest = ip.first(40 + payload_length).after(40);
  // Skip the extension headers a UDP datagram may sit behind; each one is bounds-checked.
  for (int hops = 0; hops < 8; ++hops) {
    switch (next) {
      case ip_proto_udp:
        return parse_udp(rest, out);
      case 0:    // hop-by-hop options
      case 43:   // routing
      case 60: {  // destination options
        if (!rest.has(2)) return FrameStatus::truncated;
        const std::size_t length = (std::size_t{rest.u8(1)} + 1) * 8;
        if (!rest.has(length)) return FrameStatus::truncated;
        next = rest.u8(0);
        rest = rest.after(length);
        break;
      }
      case 44:  // fragment header
        return FrameStatus::fragment;
      default:
        return FrameStatus::not_udp;
    }
  }
  return FrameStatus::malformed;
}

FrameStatus parse_ip(Bytes ip, Datagram& out, Ipv4Fragment* fragment) noexcept {
  if (!ip.has(1)) return FrameStatus::truncated;
  switch (ip.u8(0) >> 4) {
    case 4: return parse_ipv4(ip, out, fragment);
    case 6: return parse_ipv6(ip, out);
    default: return FrameStatus::not_ip;
  }
}

// Follows VLAN tags (802.1Q, QinQ) from an EtherType to the network layer.
FrameStatus parse_ethertype(std::uint16_t type, Bytes rest, Datagram& out,
                            Ipv4Fragment* fragment) noexcept {
  for (int tags = 0; tags <= max_vlan_tags; ++tags) {
    switch (type) {
      case ethertype_ipv4: return parse_ipv4(rest, out, fragment);
      case ethertype_ipv6: return parse_ipv6(rest, out);
      case ethertype_vlan:
      case ethertype_qinq:
      case ethertype_qinq_old:
        if (!rest.has(4)) return FrameStatus::truncated;
        type = rest.be16(2);  // after the 2-byte tag control information
        rest = rest.after(4);
        break;
      default: return FrameStatus::not_ip;
    }
  }
  return FrameStatus::malformed;  // more tags than any real network stacks
}

FrameStatus parse_ethernet(Bytes frame, Datagram& out, Ipv4Fragment* fragment) noexcept {
  if (!frame.has(14)) return FrameStatus::truncated;
  const std::uint16_t type = frame.be16(12);
  if (type <= 1500) return FrameStatus::not_ip;  // an 802.3 length field: LLC/SNAP, not IP here
  return parse_ethertype(type, frame.after(14), out, fragment);
}

FrameStatus parse_bsd_loopback(Bytes frame, bool network_order, Datagram& out,
                               Ipv4Fragment* fragment) noexcept {
  if (!frame.has(4)) return FrameStatus::truncated;
  // The family is in the capturing host's byte order for DLT_NULL: accept either.
  const std::uint32_t family = network_order ? frame.be32(0) : frame.le32(0);
  const std::uint32_t swapped = network_order ? frame.le32(0) : frame.be32(0);
  auto is = [&](std::uint32_t value) { return family == value || swapped == value; };
  if (is(2)) return parse_ipv4(frame.after(4), out, fragment);
  if (is(24) || is(28) || is(30) || is(10)) return parse_ipv6(frame.after(4), out);  // BSDs, Linux
  return FrameStatus::not_ip;
}

}  // namespace

bool is_supported(LinkType link) noexcept {
  switch (link.dlt) {
    case dlt_null:
    case dlt_en10mb:
    case dlt_raw:
    case dlt_loop:
    case dlt_linux_sll:
    case dlt_ipv4:
    case dlt_ipv6:
    case dlt_linux_sll2: return true;
    default: return false;
  }
}

std::string describe(LinkType link) {
  const char* name = pcap_datalink_val_to_name(link.dlt);
  const char* description = pcap_datalink_val_to_description(link.dlt);
  if (name == nullptr) return "DLT " + std::to_string(link.dlt);
  std::string text = name;
  if (description != nullptr) text += std::string(" (") + description + ")";
  return text;
}

std::string supported_link_types() {
  return "Ethernet (with VLAN tags), Linux cooked SLL and SLL2, raw IPv4/IPv6, BSD loopback";
}

std::string Endpoint::to_string() const {
  char text[INET6_ADDRSTRLEN] = {};
  if (ip_version == 4) {
    inet_ntop(AF_INET, address.data(), text, sizeof text);
    return std::string(text) + ":" + std::to_string(port);
  }
  if (ip_version == 6) {
    inet_ntop(AF_INET6, address.data(), text, sizeof text);
    // Not `"[" + std::string(text)`: GCC 12 at -O3 warns (-Wrestrict, GCC bug 105651) inside
    // operator+(const char*, string&&).
    return std::string("[") + text + "]:" + std::to_string(port);
  }
  return "?:" + std::to_string(port);
}

FrameStatus parse_reassembled(const Ipv4Fragment& first, std::span<const std::byte> ip_payload,
                              Datagram& out) noexcept {
  out.source = {};
  out.destination = {};
  out.source.ip_version = out.destination.ip_version = 4;
  for (std::size_t i = 0; i < 4; ++i) {
    out.source.address[i] = first.source[i];
    out.destination.address[i] = first.destination[i];
  }
  return parse_udp(Bytes(ip_payload), out);
}

const char* to_string(FrameStatus status) noexcept {
  switch (status) {
    case FrameStatus::ok: return "ok";
    case FrameStatus::not_ip: return "not IP";
    case FrameStatus::not_udp: return "not UDP";
    case FrameStatus::fragment: return "IP fragment";
    case FrameStatus::truncated: return "truncated";
    case FrameStatus::malformed: return "malformed";
    case FrameStatus::unsupported_link: return "unsupported link type";
  }
  return "unknown";
}

FrameStatus parse_frame(LinkType link, std::span<const std::byte> frame, Datagram& out,
                        Ipv4Fragment* fragment) noexcept {
  const Bytes bytes(frame);
  switch (link.dlt) {
    case dlt_en10mb: return parse_ethernet(bytes, out, fragment);
    case dlt_linux_sll:
      // packet type, ARPHRD, address length, 8 address bytes, then the protocol (an EtherType).
      if (!bytes.has(16)) return FrameStatus::truncated;
      return parse_ethertype(bytes.be16(14), bytes.after(16), out, fragment);
    case dlt_linux_sll2:
      // protocol first, then reserved, ifindex, ARPHRD, packet type, address length, address.
      if (!bytes.has(20)) return FrameStatus::truncated;
      return parse_ethertype(bytes.be16(0), bytes.after(20), out, fragment);
    case dlt_raw: return parse_ip(bytes, out, fragment);
    case dlt_ipv4: return parse_ipv4(bytes, out, fragment);
    case dlt_ipv6: return parse_ipv6(bytes, out);
    case dlt_null: return parse_bsd_loopback(bytes, false, out, fragment);
    case dlt_loop: return parse_bsd_loopback(bytes, true, out, fragment);
    default: return FrameStatus::unsupported_link;
  }
}

}  // namespace sim::pcap
