// SPDX-License-Identifier: Apache-2.0
// Reads the UDP datagrams of a capture file (pcap or pcapng, microsecond or nanosecond
// timestamps) with libpcap, optionally keeping only one UDP port. IPv4 fragments are
// reassembled (ip_reassembly.hpp: bounded memory, capture-time timeouts, absurd ones refused).
// Frames that hold no datagram (ARP, TCP, frames cut by the snaplen) are skipped and counted, so a
// mixed capture replays; a file libpcap cannot read, a link type the parser does not know, or a
// file cut in the middle of a record is an error, with the message saying what to do.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "sim/pcap/link_layer.hpp"
#include "sim/result.hpp"

namespace sim::pcap {

struct CaptureOptions {
  // Keep only datagrams whose source or destination port is this one. It is compiled into a BPF
  // filter (so libpcap drops other traffic before it is copied) and checked again after parsing.
  std::optional<std::uint16_t> port;
  // An extra BPF expression in tcpdump syntax (e.g. "src host 192.168.1.201"), ANDed with the
  // port. Empty: none.
  std::string filter;
};

struct CaptureStats {
  std::uint64_t records = 0;     // records read from the file (after the BPF filter)
  std::uint64_t datagrams = 0;   // UDP datagrams returned
  std::uint64_t other_port = 0;  // UDP datagrams on another port than CaptureOptions::port
  std::uint64_t not_ip = 0;
  std::uint64_t not_udp = 0;
  std::uint64_t fragments = 0;              // IPv4 fragment records
  std::uint64_t fragments_reassembled = 0;  // of those, the ones that went into datagrams
  std::uint64_t reassembled = 0;            // datagrams rebuilt from fragments (in `datagrams`)
  std::uint64_t fragments_incomplete = 0;   // datagrams dropped incomplete (timeout, room, end)
  std::uint64_t fragments_refused = 0;      // fragments of absurd size or offset
  std::uint64_t truncated = 0;   // records shorter than their headers say (snaplen)
  std::uint64_t malformed = 0;
  std::uint64_t skipped() const noexcept {
    return other_port + not_ip + not_udp + (fragments - fragments_reassembled) + truncated + malformed;
  }
};

enum class NextStatus {
  datagram,  // `out` holds the next datagram; its payload stays valid until the next call
  end,       // the end of the file
  error,     // the file cannot be read further; error() says why
};

class CaptureReader {
 public:
  // Opens a capture file by path.
  static Expected<CaptureReader> open(const std::string& path, const CaptureOptions& options = {});
  // Reads a capture from an open stdio stream (a pipe, or fmemopen() in the fuzzer); the
  // reader takes ownership and closes it. `name` is used in messages.
  static Expected<CaptureReader> open(std::FILE* stream, const std::string& name,
                                      const CaptureOptions& options = {});

  CaptureReader(CaptureReader&&) noexcept;
  CaptureReader& operator=(CaptureReader&&) noexcept;
  CaptureReader(const CaptureReader&) = delete;
  CaptureReader& operator=(const CaptureReader&) = delete;
  ~CaptureReader();

  NextStatus next(Datagram& out) noexcept;
  // Why next() returned NextStatus::error.
  const Error& error() const noexcept;

  // How much of the file has been read, 0–1, for progress lines; negative when the size is
  // unknown (a pipe, a memory stream).
  double progress() const noexcept;

  LinkType link_type() const noexcept;
  const CaptureStats& stats() const noexcept;
  // The capture's name as given to open(), for messages.
  const std::string& name() const noexcept;

  struct Impl;

 private:
  explicit CaptureReader(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// The BPF expression CaptureOptions compile to ("" when there is nothing to filter): UDP on the
// port whether the frame carries zero, one or two VLAN tags, and all IPv6 (BPF cannot see UDP
// behind extension headers; next() checks the port). The user's filter is ANDed in front.
std::string bpf_expression(const CaptureOptions& options, LinkType link);

}  // namespace sim::pcap
