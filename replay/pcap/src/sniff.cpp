// SPDX-License-Identifier: Apache-2.0
#include "sniff.hpp"

#include <utility>

namespace sim::pcap {

Sniff Sniff::read(const std::string& file, const CaptureOptions& options) {
  Sniff sniff(file, options);
  auto reader = CaptureReader::open(file, options);
  if (!reader) {
    sniff.error_ = reader.error();
    return sniff;
  }
  sniff.reader_.emplace(std::move(reader.value()));
  sniff.payloads_.reserve(head_size);
  sniff.head_.reserve(head_size);
  Datagram datagram;
  while (sniff.head_.size() < head_size) {
    const NextStatus status = sniff.reader_->next(datagram);
    if (status == NextStatus::end) break;
    if (status == NextStatus::error) {
      sniff.error_ = sniff.reader_->error();
      break;
    }
    // The reader's payload lives until its next datagram: the head keeps a copy.
    auto& bytes = sniff.payloads_.emplace_back(datagram.payload.begin(), datagram.payload.end());
    datagram.payload = bytes;
    sniff.head_.push_back(datagram);
  }
  return sniff;
}

std::uint32_t Sniff::count(const std::function<bool(std::span<const std::uint8_t>)>& is_family_packet) const {
  std::uint32_t packets = 0;
  for (const Datagram& datagram : head_) {
    const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(datagram.payload.data()),
                                              datagram.payload.size());
    packets += is_family_packet(bytes) ? 1 : 0;
  }
  return packets;
}

Expected<bool> Sniff::find(const std::function<bool(const Datagram&)>& visit) {
  seen_ = 0;
  for (const Datagram& datagram : head_) {
    ++seen_;
    if (visit(datagram)) return true;
  }
  if (error_) return *error_;
  return read_on(visit);
}

// Past the head: from where the head stopped, or (a second find) from the capture's start
// again, stepping over the head's datagrams.
Expected<bool> Sniff::read_on(const std::function<bool(const Datagram&)>& visit) {
  Datagram datagram;
  if (read_past_head_) {
    auto reader = CaptureReader::open(file_, options_);
    if (!reader) return reader.error();
    reader_.emplace(std::move(reader.value()));
    for (std::size_t i = 0; i < head_.size(); ++i) {
      if (reader_->next(datagram) != NextStatus::datagram) return false;
    }
  }
  read_past_head_ = true;
  for (;;) {
    const NextStatus status = reader_->next(datagram);
    if (status == NextStatus::end) return false;
    if (status == NextStatus::error) return reader_->error();
    ++seen_;
    if (visit(datagram)) return true;
  }
}

const CaptureStats& Sniff::stats() const noexcept {
  static const CaptureStats none;
  return reader_ ? reader_->stats() : none;
}

}  // namespace sim::pcap
