// SPDX-License-Identifier: Apache-2.0
#include "ip_reassembly.hpp"

#include <algorithm>
#include <cstring>

namespace sim::pcap {

Ipv4Reassembler::Ipv4Reassembler(ReassemblyLimits limits) : limits_(limits) {
  slots_.resize(std::max<std::size_t>(1, limits_.max_pending));
}

std::size_t Ipv4Reassembler::pending() const noexcept {
  return static_cast<std::size_t>(std::count_if(slots_.begin(), slots_.end(), [](const Pending& p) { return p.used; }));
}

void Ipv4Reassembler::drop(Pending& entry) noexcept { entry.used = false; }

void Ipv4Reassembler::expire(std::int64_t capture_ns) noexcept {
  for (Pending& p : slots_) {
    // Capture time may step back (merged files): only a datagram older by the timeout expires.
    if (p.used && capture_ns - p.first_ns > limits_.timeout_ns) {
      drop(p);
      ++counters_.timed_out;
    }
  }
}

Ipv4Reassembler::Pending* Ipv4Reassembler::find_or_start(const Ipv4Fragment& f,
                                                         std::int64_t capture_ns) noexcept {
  Pending* free_slot = nullptr;
  Pending* oldest = nullptr;
  for (Pending& p : slots_) {
    if (p.used && p.id == f.id && p.protocol == f.protocol && p.source == f.source &&
        p.destination == f.destination) {
      return &p;
    }
    if (!p.used && free_slot == nullptr) free_slot = &p;
    if (p.used && (oldest == nullptr || p.first_ns < oldest->first_ns)) oldest = &p;
  }
  if (free_slot == nullptr) {
    drop(*oldest);
    ++counters_.evicted;
    free_slot = oldest;
  }
  Pending& p = *free_slot;
  if (p.data.empty()) {
    // Once per slot for the reader's lifetime; a bad_alloc here would end the replay anyway.
    p.data.resize(max_payload);
    p.has_block.resize(blocks);
  }
  p.used = true;
  p.source = f.source;
  p.destination = f.destination;
  p.id = f.id;
  p.protocol = f.protocol;
  p.first_ns = capture_ns;
  p.total = 0;
  p.covered_blocks = 0;
  p.fragments = 0;
  std::fill(p.has_block.begin(), p.has_block.end(), std::uint8_t{0});
  return &p;
}

std::span<const std::byte> Ipv4Reassembler::add(const Ipv4Fragment& f, std::int64_t capture_ns) noexcept {
  expire(capture_ns);
  const std::size_t end = std::size_t{f.offset} + f.data.size();
  // Absurd fragments: past the largest IPv4 datagram, empty, or a middle piece not in 8-byte units.
  if (end > max_payload || f.data.empty() || (f.more && f.data.size() % 8 != 0)) {
    ++counters_.refused;
    return {};
  }
  Pending* p = find_or_start(f, capture_ns);
  if (!f.more) {
    if (p->total != 0 && p->total != end) {  // two different ends: damaged, drop all of it
      ++counters_.refused;
      drop(*p);
      return {};
    }
    p->total = end;
  }
  if (p->total != 0 && end > p->total) {
    ++counters_.refused;
    drop(*p);
    return {};
  }
  std::memcpy(p->data.data() + f.offset, f.data.data(), f.data.size());
  ++p->fragments;
  // Overlapping fragments overwrite (the later wins, as Linux does for identical resends).
  for (std::size_t b = f.offset / 8; b < (end + 7) / 8; ++b) {
    if (p->has_block[b] == 0) {
      p->has_block[b] = 1;
      ++p->covered_blocks;
    }
  }
  if (p->total == 0 || p->covered_blocks != (p->total + 7) / 8) return {};
  ++counters_.completed;
  counters_.fragments_used += p->fragments;
  drop(*p);  // the slot's bytes stay valid until the next call
  return {p->data.data(), p->total};
}

void Ipv4Reassembler::finish() noexcept {
  for (Pending& p : slots_) {
    if (p.used) {
      drop(p);
      ++counters_.abandoned;
    }
  }
}

}  // namespace sim::pcap
