// SPDX-License-Identifier: Apache-2.0
// The MCAP container format (https://mcap.dev/spec, major version 0): record opcodes, the magic
// bytes and the record types SIM reads and writes. Only the subset SIM needs: attachments and
// metadata records are skipped by the reader and never written.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sim::mcap {

// 0x89 'M' 'C' 'A' 'P' '0' '\r' '\n', at the start and at the end of every file.
inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

enum class Opcode : std::uint8_t {
  invalid = 0x00,
  header = 0x01,
  footer = 0x02,
  schema = 0x03,
  channel = 0x04,
  message = 0x05,
  chunk = 0x06,
  message_index = 0x07,
  chunk_index = 0x08,
  attachment = 0x09,
  attachment_index = 0x0A,
  statistics = 0x0B,
  metadata = 0x0C,
  metadata_index = 0x0D,
  summary_offset = 0x0E,
  data_end = 0x0F,
};

enum class Compression { none, lz4, zstd };

// "", "lz4", "zstd": the names chunks carry.
std::string_view to_string(Compression compression) noexcept;
// Accepts the chunk names and "none"; nullopt for anything else.
std::optional<Compression> parse_compression(std::string_view name) noexcept;

// A string from a file (topic, schema name, compression name…) made safe to print on a terminal:
// control characters (C0, DEL, C1) and bytes that are not UTF-8 become \xNN, so a crafted file
// cannot send escape sequences to the user's terminal.
std::string printable(std::string_view text);

struct Schema {
  std::uint16_t id = 0;  // never 0
  std::string name;      // "sensor_msgs/msg/PointCloud2"
  std::string encoding;  // "ros2msg"
  std::string data;      // the schema text
};

using Metadata = std::map<std::string, std::string>;

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;   // 0: no schema
  std::string topic;             // "/lidar_top"
  std::string message_encoding;  // "cdr"
  Metadata metadata;
};

struct MessageHeader {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;      // ns since the epoch: when the message was logged
  std::uint64_t publish_time = 0;  // ns since the epoch: when it was published
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t metadata_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

}  // namespace sim::mcap
