// SPDX-License-Identifier: Apache-2.0
// Little-endian record fields in and out of byte buffers. MCAP is little-endian throughout; the
// reader never trusts a length: every read is checked against what is left.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

#include "sim/mcap/format.hpp"

namespace sim::mcap::detail {

static_assert(std::endian::native == std::endian::little, "MCAP fields are copied as-is");

// Appends fields to a growing buffer; records are opened and closed so their length is patched.
class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::byte>& out) noexcept : out_(out) {}

  template <typename T>
  void put(T value) {
    const auto at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &value, sizeof(T));
  }
  void bytes(std::span<const std::byte> data) { out_.insert(out_.end(), data.begin(), data.end()); }
  void bytes(std::string_view text) { bytes(std::as_bytes(std::span(text.data(), text.size()))); }
  void string(std::string_view text) {
    put(static_cast<std::uint32_t>(text.size()));
    bytes(text);
  }
  // Opcode and a length placeholder; returns where the content starts.
  std::size_t open_record(Opcode op) {
    put(static_cast<std::uint8_t>(op));
    put(std::uint64_t{0});
    return out_.size();
  }
  void close_record(std::size_t content_start) {
    const std::uint64_t length = out_.size() - content_start;
    std::memcpy(out_.data() + content_start - sizeof length, &length, sizeof length);
  }
  // A u32 byte-length prefix for maps and arrays: opened, then closed like a record.
  std::size_t open_u32_block() {
    put(std::uint32_t{0});
    return out_.size();
  }
  void close_u32_block(std::size_t start) {
    const auto length = static_cast<std::uint32_t>(out_.size() - start);
    std::memcpy(out_.data() + start - sizeof length, &length, sizeof length);
  }
  std::size_t size() const noexcept { return out_.size(); }

 private:
  std::vector<std::byte>& out_;
};

// Reads fields from a span; any read past the end sets failed() and yields zeros.
class ByteReader {
 public:
  explicit ByteReader(std::span<const std::byte> data) noexcept : data_(data) {}

  template <typename T>
  T get() noexcept {
    T value{};
    if (!has(sizeof(T))) return value;
    std::memcpy(&value, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  std::span<const std::byte> bytes(std::uint64_t n) noexcept {
    if (!has(n)) return {};
    auto out = data_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return out;
  }
  std::string_view string() noexcept {
    const auto n = get<std::uint32_t>();
    const auto b = bytes(n);
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  std::span<const std::byte> rest() noexcept { return bytes(remaining()); }
  bool has(std::uint64_t n) noexcept {
    if (failed_ || n > data_.size() - pos_) {
      failed_ = true;
      return false;
    }
    return true;
  }
  std::size_t remaining() const noexcept { return data_.size() - pos_; }
  std::size_t position() const noexcept { return pos_; }
  bool failed() const noexcept { return failed_; }

 private:
  std::span<const std::byte> data_;
  std::size_t pos_ = 0;
  bool failed_ = false;
};

}  // namespace sim::mcap::detail
