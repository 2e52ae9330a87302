// SPDX-License-Identifier: Apache-2.0
// Fuzzes the MCAP reader with whole files: it must never crash, hang or read out of bounds, and
// every message it delivers must lie inside the memory it owns. Seeds (corpus/): small files the
// writer made with each compression, see tests/mcap/README.md.
#include <cstddef>
#include <cstdint>
#include <span>

#include "sim/mcap/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto reader = sim::mcap::Reader::from_bytes(
      std::span(reinterpret_cast<const std::byte*>(data), size));
  if (!reader) return 0;
  std::uint64_t sum = 0;
  for (const auto& [id, channel] : reader->channels()) {
    sum += channel.topic.size();
    if (const auto* schema = reader->schema_of(channel)) sum += schema->data.size();
  }
  while (auto message = reader->next()) {
    for (const std::byte b : message->data) sum += static_cast<std::uint8_t>(b);
  }
  static volatile std::uint64_t sink;  // keeps the reads from being optimised away
  sink = sink + sum;
  return 0;
}
