// SPDX-License-Identifier: Apache-2.0
// Writes an MCAP file: magic, Header, Schema and Channel records as they are added, Messages in
// compressed Chunks each followed by its Message Index records, then Data End (with the data
// section's CRC), a summary (schemas, channels, Statistics, Chunk Indexes), Summary Offsets, the
// Footer and the closing magic. Foxglove, the mcap CLI and @mcap/core read it with its indexes.
// One thread at a time: sim_record gives it a thread of its own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sim/mcap/format.hpp"
#include "sim/result.hpp"

namespace sim::mcap {

struct WriterOptions {
  std::string profile = "ros2";
  std::string library = "sim-mcap";
  Compression compression = Compression::zstd;
  // A chunk is compressed and written once its records pass this size (a larger message makes a
  // chunk of its own).
  std::uint64_t chunk_size = 4u << 20;
  int zstd_level = 1;  // fastest: a recorder must keep up with the sensors first
  bool crc = true;     // CRCs of chunks, the data section and the summary (0 = not computed)
  // Copies of the Schema and Channel records in the summary (MCAP makes them optional; other
  // writers may leave them out, and readers must then read the data section).
  bool repeat_schemas = true;
  bool repeat_channels = true;
};

// Messages of one channel whose chunk reached the file, and the bytes of their data.
struct StoredMessages {
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
};

class Writer {
 public:
  // Creates (or truncates) `path` and writes the magic and Header.
  static Expected<Writer> create(const std::string& path, const WriterOptions& options = {});

  Writer(Writer&&) noexcept;
  Writer& operator=(Writer&&) noexcept;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  ~Writer();  // closes the file if close() was not called; errors are lost then

  // Ids are given out from 1 in order.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding, const Metadata& metadata);

  // Adds one message to the open chunk. An error (disk full…) is final: the writer stops.
  std::optional<Error> write(const MessageHeader& header, std::span<const std::byte> data);

  // Flushes the last chunk and writes the summary and footer. Idempotent.
  std::optional<Error> close();

  const Statistics& statistics() const noexcept;
  std::uint64_t bytes_written() const noexcept;  // file size so far (after a failure: what reached it)
  // What of a channel is in the file: messages of chunks written whole (a message in the open
  // chunk, or in a chunk whose write failed, is not).
  StoredMessages stored(std::uint16_t channel_id) const;

  struct Impl;

 private:
  explicit Writer(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::mcap
