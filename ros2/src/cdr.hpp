// SPDX-License-Identifier: Apache-2.0
// XCDR1 little-endian primitives: the writer of a message prefix and a bounds-checked reader.
// Alignment is relative to the byte after the 4-byte encapsulation header (CDR's "origin").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>

namespace sim::ros2::cdr {

inline constexpr std::size_t encapsulation_size = 4;
// CDR_LE with no options: what rmw_fastrtps and rmw_cyclonedds write on little-endian hosts.
inline constexpr std::byte encapsulation_le[4] = {std::byte{0x00}, std::byte{0x01}, std::byte{0x00},
                                                  std::byte{0x00}};

// Writes into a fixed buffer; overflow() tells the caller the buffer was too small (nothing past
// it is written).
class Writer {
 public:
  explicit Writer(std::span<std::byte> out) noexcept : out_(out) {
    put(encapsulation_le, sizeof encapsulation_le);
  }
  // Position relative to the origin (after the encapsulation header).
  std::size_t offset() const noexcept { return pos_ - encapsulation_size; }
  std::size_t size() const noexcept { return pos_; }
  bool overflow() const noexcept { return overflow_; }

  void align(std::size_t n) noexcept {
    while (offset() % n != 0) u8(0);
  }
  void u8(std::uint8_t v) noexcept { put(&v, 1); }
  void u16(std::uint16_t v) noexcept { aligned_le(v); }
  void u32(std::uint32_t v) noexcept { aligned_le(v); }
  void i32(std::int32_t v) noexcept { aligned_le(static_cast<std::uint32_t>(v)); }
  void f64(double v) noexcept {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    aligned_le(bits);
  }
  // uint32 length counting the terminating NUL, the characters, the NUL.
  void string(std::string_view s) noexcept {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    put(s.data(), s.size());
    u8(0);
  }

 private:
  template <typename T>
  void aligned_le(T v) noexcept {
    align(sizeof(T));
    unsigned char b[sizeof(T)];
    for (std::size_t i = 0; i < sizeof(T); ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    put(b, sizeof(T));
  }
  void put(const void* p, std::size_t n) noexcept {
    if (n == 0) return;  // an empty string_view may hold a null pointer, which memcpy must not see
    if (overflow_ || n > out_.size() - pos_) {
      overflow_ = true;
      return;
    }
    std::memcpy(out_.data() + pos_, p, n);
    pos_ += n;
  }
  std::span<std::byte> out_;
  std::size_t pos_ = 0;
  bool overflow_ = false;
};

// Reads from a received message. The first failure is remembered as a sentence fragment naming
// the field, every later read returns zeros, so a parser reads straight through and checks once.
class Reader {
 public:
  explicit Reader(std::span<const std::byte> in) noexcept : in_(in) {}

  // Checks the encapsulation header; false (with failure()) unless it is XCDR1 little endian.
  bool encapsulation() noexcept {
    sentence_ = true;
    if (in_.size() < encapsulation_size) return fail("the message is shorter than its 4-byte header");
    const auto b0 = std::to_integer<unsigned>(in_[0]);
    const auto b1 = std::to_integer<unsigned>(in_[1]);
    if (b0 != 0 || b1 != 1) {
      if (b0 == 0 && b1 == 0) return fail("the message is big-endian CDR; only little-endian XCDR1 is read");
      return fail("the message is not XCDR1 little-endian CDR (its header is not 00 01); publish it "
                  "with the XCDR1 representation ROS 2 uses");
    }
    sentence_ = false;
    pos_ = encapsulation_size;
    return true;
  }
  bool ok() const noexcept { return failure_ == nullptr; }
  // The field that failed to read, or (when failure_is_sentence()) a whole explanation.
  const char* failure() const noexcept { return failure_; }
  bool failure_is_sentence() const noexcept { return sentence_; }
  std::size_t remaining() const noexcept { return ok() ? in_.size() - pos_ : 0; }

  std::uint8_t u8(const char* what) noexcept { return read_le<std::uint8_t>(what); }
  std::uint16_t u16(const char* what) noexcept { return read_le<std::uint16_t>(what); }
  std::uint32_t u32(const char* what) noexcept { return read_le<std::uint32_t>(what); }
  std::int32_t i32(const char* what) noexcept {
    return static_cast<std::int32_t>(read_le<std::uint32_t>(what));
  }
  bool boolean(const char* what) noexcept { return u8(what) != 0; }
  double f64(const char* what) noexcept {
    const std::uint64_t bits = read_le<std::uint64_t>(what);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  // A CDR string; its length must fit the message and its last byte must be the NUL.
  std::string_view string(const char* what) noexcept {
    const std::uint32_t n = u32(what);
    if (!ok()) return {};
    if (n == 0) return {};  // some writers send an empty string as length 0
    if (n > remaining()) {
      fail(what);
      return {};
    }
    const char* p = reinterpret_cast<const char*>(in_.data() + pos_);
    if (p[n - 1] != '\0') {
      fail(what);
      return {};
    }
    pos_ += n;
    return {p, n - 1};
  }
  // A uint8[] sequence: a uint32 count then the bytes, all inside the message.
  std::span<const std::byte> bytes(const char* what) noexcept {
    const std::uint32_t n = u32(what);
    if (!ok()) return {};
    if (n > remaining()) {
      fail(what);
      return {};
    }
    const auto out = in_.subspan(pos_, n);
    pos_ += n;
    return out;
  }
  // A fixed-size array of bytes (octet[n]): no count, no alignment.
  std::span<const std::byte> fixed(std::size_t n, const char* what) noexcept {
    if (!ok()) return {};
    if (n > remaining()) {
      fail(what);
      return {};
    }
    const auto out = in_.subspan(pos_, n);
    pos_ += n;
    return out;
  }
  bool fail(const char* what) noexcept {
    if (failure_ == nullptr) failure_ = what;
    return false;
  }

 private:
  template <typename T>
  T read_le(const char* what) noexcept {
    if (!ok()) return 0;
    std::size_t pos = pos_;
    const std::size_t origin = encapsulation_size;
    while ((pos - origin) % sizeof(T) != 0) ++pos;
    if (pos > in_.size() || sizeof(T) > in_.size() - pos) {
      fail(what);
      return 0;
    }
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const auto byte = static_cast<T>(std::to_integer<unsigned>(in_[pos + i]));
      v = static_cast<T>(v | static_cast<T>(byte << (8 * i)));
    }
    pos_ = pos + sizeof(T);
    return v;
  }
  std::span<const std::byte> in_;
  std::size_t pos_ = 0;
  const char* failure_ = nullptr;
  bool sentence_ = false;
};

}  // namespace sim::ros2::cdr
