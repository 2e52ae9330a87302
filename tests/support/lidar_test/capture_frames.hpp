// SPDX-License-Identifier: Apache-2.0
// Hand-built link-layer frames and capture files for the capture-reader tests: every header
// byte is written here, so each test states exactly which encapsulation it exercises.
#pragma once

#include <pcap/pcap.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

namespace sim::pcap::testing {

using Bytes = std::vector<std::uint8_t>;

inline void put16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v & 0xff));
}
inline Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

inline Bytes payload_of(std::size_t size, std::uint8_t seed) {
  Bytes b(size);
  for (std::size_t i = 0; i < size; ++i) b[i] = static_cast<std::uint8_t>(seed + i);
  return b;
}

inline Bytes udp(std::uint16_t src_port, std::uint16_t dst_port, const Bytes& payload) {
  Bytes b;
  put16(b, src_port);
  put16(b, dst_port);
  put16(b, static_cast<std::uint16_t>(8 + payload.size()));
  put16(b, 0);  // checksum: optional over IPv4
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

// An IPv4 header with `options` (a multiple of 4 bytes) in front of `body`.
inline Bytes ipv4(std::array<std::uint8_t, 4> src, std::array<std::uint8_t, 4> dst,
                  const Bytes& body, std::uint8_t protocol = 17, const Bytes& options = {},
                  std::uint16_t flags_fragment = 0x4000 /* don't fragment */) {
  if (options.size() % 4 != 0 || options.size() > 40) throw std::invalid_argument("options");
  const std::size_t header = 20 + options.size();
  Bytes b;
  b.push_back(static_cast<std::uint8_t>(0x40 | (header / 4)));
  b.push_back(0);
  put16(b, static_cast<std::uint16_t>(header + body.size()));
  put16(b, 0x1234);
  put16(b, flags_fragment);
  b.push_back(64);
  b.push_back(protocol);
  put16(b, 0);  // header checksum: not checked by readers of captures
  b.insert(b.end(), src.begin(), src.end());
  b.insert(b.end(), dst.begin(), dst.end());
  b.insert(b.end(), options.begin(), options.end());
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

inline Bytes ipv6(std::uint8_t last_src, std::uint8_t last_dst, const Bytes& body,
                  std::uint8_t next_header = 17) {
  Bytes b = {0x60, 0, 0, 0};
  put16(b, static_cast<std::uint16_t>(body.size()));
  b.push_back(next_header);
  b.push_back(64);
  Bytes src(16, 0), dst(16, 0);
  src[0] = dst[0] = 0xfe;
  src[1] = dst[1] = 0x80;
  src[15] = last_src;
  dst[15] = last_dst;
  b.insert(b.end(), src.begin(), src.end());
  b.insert(b.end(), dst.begin(), dst.end());
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

inline Bytes ethernet(std::uint16_t ethertype, const Bytes& body,
                      std::initializer_list<std::pair<std::uint16_t, std::uint16_t>> tags = {}) {
  Bytes b = {0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x00, 0x1b, 0x21, 0x01, 0x02, 0x03};
  for (const auto& [tpid, tci] : tags) {
    put16(b, tpid);
    put16(b, tci);
  }
  put16(b, ethertype);
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

inline Bytes sll(std::uint16_t protocol, const Bytes& body) {
  Bytes b;
  put16(b, 0);      // packet type: to us
  put16(b, 1);      // ARPHRD_ETHER
  put16(b, 6);      // address length
  Bytes address = {0x00, 0x1b, 0x21, 0x01, 0x02, 0x03, 0, 0};
  b.insert(b.end(), address.begin(), address.end());
  put16(b, protocol);
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

inline Bytes sll2(std::uint16_t protocol, const Bytes& body) {
  Bytes b;
  put16(b, protocol);
  put16(b, 0);                      // reserved
  Bytes ifindex = {0, 0, 0, 3};
  b.insert(b.end(), ifindex.begin(), ifindex.end());
  put16(b, 1);                      // ARPHRD_ETHER
  b.push_back(0);                   // packet type
  b.push_back(6);                   // address length
  Bytes address = {0x00, 0x1b, 0x21, 0x01, 0x02, 0x03, 0, 0};
  b.insert(b.end(), address.begin(), address.end());
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

struct Record {
  Bytes frame;
  std::int64_t timestamp_ns = 0;
  std::uint32_t original_length = 0;  // 0: the frame's size (not cut by a snaplen)
};

// Writes records with libpcap's own writer, at the given timestamp precision.
inline void write_capture(const std::string& path, int dlt, const std::vector<Record>& records,
                          bool nanosecond = false) {
  const int precision = nanosecond ? PCAP_TSTAMP_PRECISION_NANO : PCAP_TSTAMP_PRECISION_MICRO;
  pcap_t* dead = pcap_open_dead_with_tstamp_precision(dlt, 65535, static_cast<u_int>(precision));
  if (dead == nullptr) throw std::runtime_error("pcap_open_dead failed");
  pcap_dumper_t* dumper = pcap_dump_open(dead, path.c_str());
  if (dumper == nullptr) throw std::runtime_error(std::string("pcap_dump_open: ") + pcap_geterr(dead));
  for (const Record& r : records) {
    pcap_pkthdr header{};
    header.ts.tv_sec = r.timestamp_ns / 1'000'000'000;
    const std::int64_t fraction = r.timestamp_ns % 1'000'000'000;
    header.ts.tv_usec = static_cast<suseconds_t>(nanosecond ? fraction : fraction / 1000);
    header.caplen = static_cast<bpf_u_int32>(r.frame.size());
    header.len = r.original_length != 0 ? r.original_length : header.caplen;
    pcap_dump(reinterpret_cast<u_char*>(dumper), &header, r.frame.data());
  }
  pcap_dump_close(dumper);
  pcap_close(dead);
}

}  // namespace sim::pcap::testing
