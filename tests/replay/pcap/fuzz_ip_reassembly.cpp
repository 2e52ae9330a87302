// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: IPv4 fragment reassembly (replay/pcap's Ipv4Reassembler). Input: records of
// [id u8][offset u16 in 8-byte units][flags u8: bit 0 more][time step u8][length u16][data].
// A completed datagram is never longer than the largest IPv4 payload; memory stays bounded; and
// every byte of it is the byte the latest fragment of its ID put there, so a hole is never filled
// with an earlier datagram's bytes nor two datagrams of one ID merged with other bytes.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <vector>

#include "ip_reassembly.hpp"

namespace {

// Per ID, what the fragments since its last completed datagram wrote, byte by byte.
struct Written {
  std::vector<std::byte> bytes;
  std::vector<std::uint8_t> set;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sim::pcap::Ipv4Reassembler reassembler({.max_pending = 4, .timeout_ns = 1000, .max_distance = 64});
  std::map<std::uint16_t, Written> written;
  std::int64_t now = 0;
  std::size_t at = 0;
  while (at + 7 <= size) {
    sim::pcap::Ipv4Fragment f;
    f.id = data[at];
    f.protocol = 17;
    f.offset = static_cast<std::uint32_t>(data[at + 1] | data[at + 2] << 8) * 8;
    f.more = (data[at + 3] & 1) != 0;
    now += data[at + 4];
    const std::size_t length = std::min<std::size_t>(data[at + 5] | std::size_t{data[at + 6]} << 8, size - at - 7);
    f.data = {reinterpret_cast<const std::byte*>(data + at + 7), length};
    at += 7 + length;
    const std::size_t end = std::size_t{f.offset} + length;
    const bool sane = end <= 65515 && length != 0 && (!f.more || length % 8 == 0);
    if (sane) {
      Written& w = written[f.id];
      if (w.bytes.size() < end) {
        w.bytes.resize(end);
        w.set.resize(end);
      }
      std::memcpy(w.bytes.data() + f.offset, f.data.data(), length);
      std::memset(w.set.data() + f.offset, 1, length);
    }
    const auto whole = reassembler.add(f, now);
    if (whole.size() > 65515) __builtin_trap();
    if (reassembler.pending() > 4) __builtin_trap();
    if (!whole.empty()) {
      const Written& w = written[f.id];
      if (w.bytes.size() < whole.size()) __builtin_trap();
      for (std::size_t i = 0; i < whole.size(); ++i) {
        if (w.set[i] == 0 || w.bytes[i] != whole[i]) __builtin_trap();
      }
      written.erase(f.id);
    }
  }
  reassembler.finish();
  if (reassembler.pending() != 0) __builtin_trap();
  return 0;
}
