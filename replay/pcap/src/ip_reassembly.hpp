// SPDX-License-Identifier: Apache-2.0
// IPv4 fragment reassembly for captures. A sensor's datagram above the link MTU (Ouster's are
// 6–33 kB) travels as IPv4 fragments; the kernel reassembles them for a socket, a capture holds
// them as they were on the wire. This rebuilds the datagrams as a receiving host would (RFC 791,
// RFC 815 holes), with bounded memory and time:
//   - at most `max_pending` datagrams are being rebuilt at once (more: the oldest is dropped),
//     each in a buffer allocated once and reused;
//   - a datagram not complete `timeout_ns` of capture time after its first fragment is dropped
//     (Linux's ipfrag_time is 30 s); so is whatever is pending at the end of the capture;
//   - a fragment reaching past 65,535 bytes, or with a length that is not a multiple of 8 when
//     more follow, is refused; so is a second "last" fragment that disagrees on the length, and a
//     last fragment that ends before bytes already received (the datagram is dropped);
//   - a fragment overlapping bytes already received with other bytes drops the whole datagram
//     (RFC 5722; Linux does so for IPv4 since 4.19); an identical resend is ignored;
//   - a datagram that got no fragment while `max_distance` other fragments came is stale (an IP
//     ID used again after 65,536 datagrams, within seconds at an OS-128's 2,600 datagrams/s):
//     dropped, and a fragment with its ID starts a new one (Linux: ipfrag_max_dist).
// Every drop is counted. Pure function of its input (no I/O), so it is fuzzed directly.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/pcap/link_layer.hpp"

namespace sim::pcap {

struct ReassemblyLimits {
  std::size_t max_pending = 64;
  std::int64_t timeout_ns = 30'000'000'000;
  std::uint64_t max_distance = 4096;  // fragments of any datagram
};

struct ReassemblyCounters {
  std::uint64_t completed = 0;        // datagrams rebuilt
  std::uint64_t fragments_used = 0;   // fragments that went into them
  std::uint64_t timed_out = 0;        // datagrams dropped incomplete after the timeout
  std::uint64_t evicted = 0;          // dropped incomplete to make room (max_pending)
  std::uint64_t abandoned = 0;        // incomplete at the end of the capture
  std::uint64_t refused = 0;          // fragments refused: absurd size, offset or length
  std::uint64_t overlapping = 0;      // datagrams dropped for a fragment overlapping with other bytes
  std::uint64_t stale = 0;            // dropped incomplete: no fragment for max_distance fragments
  std::uint64_t incomplete() const noexcept { return timed_out + evicted + abandoned + stale; }
};

class Ipv4Reassembler {
 public:
  explicit Ipv4Reassembler(ReassemblyLimits limits = {});

  // Adds a fragment seen at `capture_ns`. When it completes a datagram, returns the whole IP
  // payload (valid until the next call); otherwise an empty span.
  std::span<const std::byte> add(const Ipv4Fragment& fragment, std::int64_t capture_ns) noexcept;
  // The capture ended: what is pending will never complete.
  void finish() noexcept;

  const ReassemblyCounters& counters() const noexcept { return counters_; }
  std::size_t pending() const noexcept;

 private:
  static constexpr std::size_t max_payload = 65535 - 20;  // IPv4 total length minus its header
  static constexpr std::size_t blocks = (max_payload + 7) / 8;

  struct Pending {
    bool used = false;
    std::array<std::uint8_t, 4> source{};
    std::array<std::uint8_t, 4> destination{};
    std::uint16_t id = 0;
    std::uint8_t protocol = 0;
    std::int64_t first_ns = 0;
    std::size_t total = 0;  // 0 until the last fragment came
    std::size_t max_end = 0;  // the furthest byte any fragment reached
    std::uint64_t last_fragment = 0;  // fragments_seen_ when its last fragment came
    std::size_t covered_blocks = 0;
    std::uint32_t fragments = 0;
    std::vector<std::byte> data;          // max_payload bytes, allocated on first use
    std::vector<std::uint8_t> has_block;  // per 8-byte block
  };

  Pending* find_or_start(const Ipv4Fragment& fragment, std::int64_t capture_ns) noexcept;
  void expire(std::int64_t capture_ns) noexcept;
  void drop(Pending& entry) noexcept;
  bool overlaps_with_other_bytes(const Pending& entry, const Ipv4Fragment& fragment) const noexcept;

  ReassemblyLimits limits_;
  std::vector<Pending> slots_;
  ReassemblyCounters counters_;
  std::uint64_t fragments_seen_ = 0;
};

}  // namespace sim::pcap
