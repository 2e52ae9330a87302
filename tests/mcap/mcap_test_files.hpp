// SPDX-License-Identifier: Apache-2.0
// Temporary files and byte helpers for the MCAP tests: unique names (pid + counter), removed by
// the owner's destructor so parallel runs leave nothing behind.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <utility>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace sim::testing {

class TempFile {
 public:
  explicit TempFile(const std::string& suffix = ".mcap") {
    static std::atomic<int> counter{0};
    path_ = (std::filesystem::temp_directory_path() /
             ("sim_mcap_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + suffix))
                .string();
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

inline std::vector<std::byte> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(chars.size());
  for (std::size_t i = 0; i < chars.size(); ++i) out[i] = static_cast<std::byte>(chars[i]);
  return out;
}

inline void write_bytes(const std::string& path, const std::vector<std::byte>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Builds an MCAP file record by record, for files our writer never makes (unchunked messages,
// redefined ids, nested chunks…): each field little-endian, each record opcode + u64 length.
class RawMcap {
 public:
  RawMcap() {
    const unsigned char magic[] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
    for (const unsigned char c : magic) out_.push_back(static_cast<std::byte>(c));
    record(0x01, Fields().string("ros2").string("RawMcap"));
  }

  // The content of one record, field by field.
  class Fields {
   public:
    template <typename T>
    Fields& put(T value) {
      const auto at = bytes_.size();
      bytes_.resize(at + sizeof value);
      std::memcpy(bytes_.data() + at, &value, sizeof value);
      return *this;
    }
    Fields& string(const std::string& text) {
      put(static_cast<std::uint32_t>(text.size()));
      return raw(std::as_bytes(std::span(text.data(), text.size())));
    }
    Fields& raw(std::span<const std::byte> data) {
      bytes_.insert(bytes_.end(), data.begin(), data.end());
      return *this;
    }
    const std::vector<std::byte>& bytes() const { return bytes_; }

   private:
    std::vector<std::byte> bytes_;
  };

  // One whole record: what a chunk holds, or the file.
  static std::vector<std::byte> encode(std::uint8_t opcode, const Fields& content) {
    const std::uint64_t length = content.bytes().size();
    std::vector<std::byte> out(1 + sizeof length + length);
    out[0] = static_cast<std::byte>(opcode);
    std::memcpy(out.data() + 1, &length, sizeof length);
    if (length > 0) std::memcpy(out.data() + 1 + sizeof length, content.bytes().data(), length);
    return out;
  }
  RawMcap& record(std::uint8_t opcode, const Fields& content) {
    const auto r = encode(opcode, content);
    out_.insert(out_.end(), r.begin(), r.end());
    return *this;
  }
  RawMcap& schema(std::uint16_t id, const std::string& name, const std::string& text) {
    return record(0x03, Fields().put(id).string(name).string("ros2msg").string(text));
  }
  // A channel with `metadata` (key, value pairs) and message encoding cdr.
  RawMcap& channel(std::uint16_t id, std::uint16_t schema_id, const std::string& topic,
                   const std::vector<std::pair<std::string, std::string>>& metadata = {}) {
    Fields map;
    for (const auto& [key, value] : metadata) map.string(key).string(value);
    return record(0x04, Fields().put(id).put(schema_id).string(topic).string("cdr")
                            .put(static_cast<std::uint32_t>(map.bytes().size())).raw(map.bytes()));
  }
  static Fields message_fields(std::uint16_t channel, std::uint32_t sequence, std::uint64_t log_time,
                               std::span<const std::byte> data) {
    return Fields().put(channel).put(sequence).put(log_time).put(log_time).raw(data);
  }
  RawMcap& message(std::uint16_t channel, std::uint32_t sequence, std::uint64_t log_time,
                   std::span<const std::byte> data) {
    return record(0x05, message_fields(channel, sequence, log_time, data));
  }
  // An uncompressed chunk holding `records` (whole records), CRC 0 (not checked).
  RawMcap& chunk(const std::vector<std::byte>& records) {
    return record(0x06, Fields().put(std::uint64_t{0}).put(std::uint64_t{0})
                            .put(static_cast<std::uint64_t>(records.size())).put(std::uint32_t{0})
                            .string("").put(static_cast<std::uint64_t>(records.size())).raw(records));
  }
  // Data End (CRC 0), a Footer without summary, the closing magic.
  std::vector<std::byte> finish() {
    record(0x0F, Fields().put(std::uint32_t{0}));
    record(0x02, Fields().put(std::uint64_t{0}).put(std::uint64_t{0}).put(std::uint32_t{0}));
    std::vector<std::byte> out = out_;
    out.insert(out.end(), out_.begin(), out_.begin() + 8);
    return out;
  }
  const std::vector<std::byte>& bytes() const { return out_; }

 private:
  std::vector<std::byte> out_;
};

}  // namespace sim::testing
