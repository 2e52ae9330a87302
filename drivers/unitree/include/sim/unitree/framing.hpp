// SPDX-License-Identifier: Apache-2.0
// Framing layers: they cut a byte stream (UDP datagrams or serial reads, cut anywhere) into
// checked packets. L2Framer follows the L2's packet_size; MavlinkFramer follows MAVLink v2 (L1).
//
// Both are pull-style so no callback or allocation happens per packet:
//   while (!bytes.empty()) {
//     bytes = bytes.subspan(framer.feed(bytes));
//     while (auto packet = framer.next()) use(*packet);
//   }
// Their buffers are allocated once and bounded; bytes that cannot start a packet are skipped
// (counted as a resync) and every packet's checksum is verified before it is handed out.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace sim::unitree {

struct FramerCounters {
  std::uint64_t packets = 0;        // packets handed out, checksum verified
  std::uint64_t bad_crc = 0;        // complete packets whose checksum failed (dropped)
  std::uint64_t truncated = 0;      // packets cut short by the next packet or by the end of input
  std::uint64_t wrong_header = 0;   // a start marker with an impossible header (dropped)
  std::uint64_t foreign = 0;        // of those, packets of another sensor (RoboSense MSOP)
  std::uint64_t unknown = 0;        // frames of a message this decoder does not know (dropped)
  std::uint64_t resyncs = 0;        // times bytes were skipped to find the next packet start
  std::uint64_t skipped_bytes = 0;
};

// A bounded byte buffer with a read window; shared plumbing of the two framers.
class ByteWindow {
 public:
  explicit ByteWindow(std::size_t capacity) : storage_(capacity) {}
  // Copies in as many bytes as fit; returns how many.
  std::size_t append(std::span<const std::uint8_t> bytes) noexcept;
  std::span<const std::uint8_t> view() const noexcept {
    return {storage_.data() + begin_, end_ - begin_};
  }
  void consume(std::size_t n) noexcept { begin_ += n; }
  void clear() noexcept { begin_ = end_ = 0; }

 private:
  std::vector<std::uint8_t> storage_;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
};

class L2Framer {
 public:
  L2Framer();
  // Takes as many bytes as the buffer holds; returns how many (call next() until it is empty
  // before feeding the rest).
  std::size_t feed(std::span<const std::uint8_t> bytes) noexcept;
  // The next whole packet (header + data + tail) with a good CRC; valid until the next call.
  std::optional<std::span<const std::uint8_t>> next() noexcept;
  // End of input: a partial packet left in the buffer is counted as truncated and dropped.
  void finish() noexcept;
  const FramerCounters& counters() const noexcept { return counters_; }

 private:
  void skip(std::size_t n) noexcept;
  ByteWindow window_;
  std::size_t release_ = 0;  // size of the packet last handed out, dropped on the next call
  bool in_sync_ = true;
  FramerCounters counters_;
};

// MAVLink v2 messages the L1 sends (reference §8).
struct MavlinkMessageInfo {
  std::uint32_t msgid;
  std::uint8_t length;     // full (untrimmed) payload length
  std::uint8_t crc_extra;
};
// nullopt for a message id the L1 is not known to send.
std::optional<MavlinkMessageInfo> mavlink_message_info(std::uint32_t msgid) noexcept;

struct MavlinkMessage {
  std::uint32_t msgid = 0;
  std::uint8_t seq = 0;
  std::uint8_t sysid = 0;
  std::uint8_t compid = 0;
  // The payload zero-extended to the message's full length (MAVLink v2 trims trailing zeros).
  std::span<const std::uint8_t> payload;
};

class MavlinkFramer {
 public:
  static constexpr std::uint8_t kStx = 0xFD;
  static constexpr std::size_t kHeaderSize = 10;
  static constexpr std::size_t kSignatureSize = 13;

  MavlinkFramer();
  std::size_t feed(std::span<const std::uint8_t> bytes) noexcept;
  // The next message with a good CRC (including its CRC_EXTRA); valid until the next call.
  std::optional<MavlinkMessage> next() noexcept;
  void finish() noexcept;
  const FramerCounters& counters() const noexcept { return counters_; }

 private:
  void skip(std::size_t n) noexcept;
  ByteWindow window_;
  std::size_t release_ = 0;
  bool in_sync_ = true;
  std::array<std::uint8_t, 255> payload_{};
  FramerCounters counters_;
};

}  // namespace sim::unitree
