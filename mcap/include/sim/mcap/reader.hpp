// SPDX-License-Identifier: Apache-2.0
// Reads an MCAP file and trusts none of it: magic, every record length, every CRC, absurd sizes.
// A damaged file (truncated, bad CRC, garbage) is read as far as it is intact: messages of every
// intact chunk are still delivered, and problem() says in one sentence what was wrong.
// The file is memory-mapped; messages are delivered one at a time, in file order and, inside a
// chunk, in log-time order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "sim/mcap/format.hpp"
#include "sim/result.hpp"

namespace sim::mcap {

struct MessageView {
  MessageHeader header;
  std::span<const std::byte> data;  // valid until the next call to next() or rewind()
};

class Reader {
 public:
  // Fails only when the file cannot be opened or is not MCAP at all (wrong magic).
  static Expected<Reader> open(const std::string& path);
  // Reads a file already in memory; `bytes` must outlive the reader (tests, the fuzzer).
  static Expected<Reader> from_bytes(std::span<const std::byte> bytes);

  Reader(Reader&&) noexcept;
  Reader& operator=(Reader&&) noexcept;
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  ~Reader();

  const std::string& profile() const noexcept;
  const std::string& library() const noexcept;
  // Every schema and channel of the file: from its summary when the summary is intact and
  // repeats every channel with its schema, else (the summary is optional, and so are its copies)
  // from a first pass over its data section, merged with what the summary holds.
  const std::map<std::uint16_t, Schema>& schemas() const noexcept;
  const std::map<std::uint16_t, Channel>& channels() const noexcept;
  const Schema* schema_of(const Channel& channel) const noexcept;
  // The Statistics record of an intact summary.
  const std::optional<Statistics>& statistics() const noexcept;
  bool has_summary() const noexcept;
  // The earliest log time of the file: from the first pass over the data section when one was
  // needed, else from the summary's Statistics; nullopt when neither knows.
  std::optional<std::uint64_t> start_time() const noexcept;

  // The next intact message, or nullopt at the end of what can be read. Damage met on the way is
  // noted: a record that cannot be one there (a Footer inside the data section), a message on a
  // channel the file never defines, a missing Data End, fewer messages than the summary counts.
  std::optional<MessageView> next();
  // Back to the first message.
  void rewind();

  // The first problem found (one sentence), or empty while the file is intact so far; and how
  // many problems were found in all.
  const std::string& problem() const noexcept;
  std::uint64_t problem_count() const noexcept;
  // Chunks skipped because they were damaged.
  std::uint64_t skipped_chunks() const noexcept;

  struct Impl;

 private:
  explicit Reader(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// Refused beyond this: a chunk that claims more is damaged or hostile.
inline constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

}  // namespace sim::mcap
