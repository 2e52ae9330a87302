// SPDX-License-Identifier: Apache-2.0
// The capture's first datagrams, read once before any family parses its options: every family
// claims the capture from them (family.hpp), and the family that replays it finds its model in
// them, reading on past them when they hold none.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sim/pcap/capture.hpp"
#include "sim/result.hpp"

namespace sim::pcap {

class Sniff {
 public:
  // Enough for every family to show itself past another service's chatter, without holding
  // more than a few MB of Ouster datagrams.
  static constexpr std::size_t head_size = 256;

  // Reads the head of `file` through `options` (the user's --port and --filter). A capture
  // that cannot be opened or read leaves the datagrams before the damage and its error.
  static Sniff read(const std::string& file, const CaptureOptions& options);

  // The first datagrams of the capture, up to head_size; their payloads are copies.
  std::span<const Datagram> head() const noexcept { return head_; }

  // How many datagrams of the head `is_family_packet` takes for its family's (a payload as bytes).
  std::uint32_t count(const std::function<bool(std::span<const std::uint8_t>)>& is_family_packet) const;

  // Visits the capture's datagrams from its start (the head, then the rest of the file) until
  // `visit` returns true, and says whether it did. The error of a capture that cannot be read
  // as far as needed.
  Expected<bool> find(const std::function<bool(const Datagram&)>& visit);

  // Why the capture could not be opened (nullopt: it could): a family that needs no detection
  // says so before it creates its streams.
  std::optional<Error> open_error() const { return reader_ ? std::nullopt : error_; }

  // The datagrams the last find() visited, and what the reader skipped on the way.
  std::uint64_t seen() const noexcept { return seen_; }
  const CaptureStats& stats() const noexcept;

 private:
  Sniff(std::string file, CaptureOptions options) : file_(std::move(file)), options_(std::move(options)) {}
  Expected<bool> read_on(const std::function<bool(const Datagram&)>& visit);

  std::string file_;
  CaptureOptions options_;
  std::optional<CaptureReader> reader_;  // positioned after the head until find() reads on
  std::optional<Error> error_;           // the head's: opening, or reading it
  std::vector<std::vector<std::byte>> payloads_;
  std::vector<Datagram> head_;           // payloads point into payloads_
  bool read_past_head_ = false;
  std::uint64_t seen_ = 0;
};

}  // namespace sim::pcap
