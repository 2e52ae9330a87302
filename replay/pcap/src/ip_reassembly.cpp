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
      if (fragments_seen_ - p.last_fragment <= limits_.max_distance) return &p;
      drop(p);  // its ID came round again: this fragment starts a new datagram
      ++counters_.stale;
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
  p.max_end = 0;
  p.covered_blocks = 0;
  p.fragments = 0;
  std::fill(p.has_block.begin(), p.has_block.end(), std::uint8_t{0});
  return &p;
}

// Whether the fragment brings other bytes for any 8-byte block already received: blocks are
// whole (offsets are in 8-byte units, only the last fragment ends mid-block, and it sets the end).
bool Ipv4Reassembler::overlaps_with_other_bytes(const Pending& p, const Ipv4Fragment& f) const noexcept {
  const std::size_t end = std::size_t{f.offset} + f.data.size();
  for (std::size_t b = f.offset / 8; b < (end + 7) / 8; ++b) {
    if (p.has_block[b] == 0) continue;
    const std::size_t from = b * 8;
    const std::size_t to = std::min(end, std::min(from + 8, p.max_end));
    if (to > from && std::memcmp(p.data.data() + from, f.data.data() + (from - f.offset), to - from) != 0) return true;
    if (to - from < std::min<std::size_t>(8, end - from)) return true;  // a block received shorter
  }
  return false;
}

std::span<const std::byte> Ipv4Reassembler::add(const Ipv4Fragment& f, std::int64_t capture_ns) noexcept {
  expire(capture_ns);
  ++fragments_seen_;
  const std::size_t end = std::size_t{f.offset} + f.data.size();
  // Absurd fragments: past the largest IPv4 datagram, empty, or a middle piece not in 8-byte units.
  if (end > max_payload || f.data.empty() || (f.more && f.data.size() % 8 != 0)) {
    ++counters_.refused;
    return {};
  }
  Pending* p = find_or_start(f, capture_ns);
  p->last_fragment = fragments_seen_;
  if (!f.more) {
    // Two different ends, or an end before bytes already received: damaged, drop all of it.
    if ((p->total != 0 && p->total != end) || p->max_end > end) {
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
  if (overlaps_with_other_bytes(*p, f)) {
    // Not a resend: another datagram with this ID, or a forged overlap. Never merged.
    ++counters_.refused;
    ++counters_.overlapping;
    drop(*p);
    return {};
  }
  std::memcpy(p->data.data() + f.offset, f.data.data(), f.data.size());
  p->max_end = std::max(p->max_end, end);
  ++p->fragments;
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
