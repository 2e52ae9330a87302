// SPDX-License-Identifier: Apache-2.0
#include "sim/unitree/framing.hpp"

#include <algorithm>
#include <cstring>

#include "sim/unitree/bytes.hpp"
#include "sim/unitree/crc.hpp"
#include "sim/unitree/l2_protocol.hpp"

namespace sim::unitree {

std::size_t ByteWindow::append(std::span<const std::uint8_t> bytes) noexcept {
  if (storage_.size() - end_ < bytes.size() && begin_ > 0) {
    // Compact only when the tail is short: most datagrams then cost one copy, not two.
    std::memmove(storage_.data(), storage_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  const std::size_t n = std::min(bytes.size(), storage_.size() - end_);
  if (n > 0) std::memcpy(storage_.data() + end_, bytes.data(), n);
  end_ += n;
  if (begin_ == end_) begin_ = end_ = 0;
  return n;
}

namespace {

// Offset of the first place `marker` could start in `bytes`: a full match, or a prefix of it at
// the very end (more bytes may complete it). bytes.size() when there is none.
std::size_t find_marker(std::span<const std::uint8_t> bytes, std::span<const std::uint8_t> marker) {
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const std::size_t n = std::min(marker.size(), bytes.size() - i);
    if (std::equal(marker.begin(), marker.begin() + static_cast<std::ptrdiff_t>(n),
                   bytes.begin() + static_cast<std::ptrdiff_t>(i))) {
      return i;
    }
  }
  return bytes.size();
}

bool contains_marker(std::span<const std::uint8_t> bytes, std::span<const std::uint8_t> marker) {
  return std::search(bytes.begin(), bytes.end(), marker.begin(), marker.end()) != bytes.end();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// L2

// Twice the largest packet, so a whole packet always fits behind a partial one.
L2Framer::L2Framer() : window_(2 * l2::kMaxPacketSize) {}

std::size_t L2Framer::feed(std::span<const std::uint8_t> bytes) noexcept {
  window_.consume(release_);
  release_ = 0;
  return window_.append(bytes);
}

void L2Framer::skip(std::size_t n) noexcept {
  if (n == 0) return;
  if (in_sync_) ++counters_.resyncs;
  in_sync_ = false;
  counters_.skipped_bytes += n;
  window_.consume(n);
}

std::optional<std::span<const std::uint8_t>> L2Framer::next() noexcept {
  window_.consume(release_);
  release_ = 0;
  const std::span<const std::uint8_t> magic(l2::kMagic);
  for (;;) {
    std::span<const std::uint8_t> bytes = window_.view();
    const std::size_t start = find_marker(bytes, magic);
    if (start > 0) {
      skip(start);
      bytes = window_.view();
    }
    if (bytes.size() < l2::kHeaderSize) return std::nullopt;

    if (std::equal(bytes.begin() + 4, bytes.begin() + 8, std::begin(l2::kRoboSenseTag))) {
      ++counters_.wrong_header;
      ++counters_.foreign;
      skip(magic.size());
      continue;
    }
    const std::uint32_t type = le::u32(bytes, 4);
    const std::uint32_t size = le::u32(bytes, 8);
    const std::optional<std::size_t> expected = l2::expected_size(type);
    if (size < l2::kHeaderSize + l2::kTailSize || size > l2::kMaxPacketSize ||
        (expected && size != *expected)) {
      ++counters_.wrong_header;
      skip(magic.size());
      continue;
    }
    if (bytes.size() < size) return std::nullopt;

    const std::span<const std::uint8_t> packet = bytes.first(size);
    // The CRC covers the data bytes only (reference §7: three independent receivers agree; the
    // official "head and data" comment is wrong).
    const std::uint32_t stored = le::u32(packet, size - l2::kTailSize);
    const std::uint32_t computed =
        crc32(packet.subspan(l2::kHeaderSize, size - l2::kHeaderSize - l2::kTailSize));
    if (stored != computed) {
      // A packet cut short (a lost datagram) runs into the next packet's magic; skip only the
      // magic so that next packet is still found.
      if (contains_marker(packet.subspan(1), magic)) {
        ++counters_.truncated;
      } else {
        ++counters_.bad_crc;
      }
      skip(magic.size());
      continue;
    }
    ++counters_.packets;
    in_sync_ = true;
    release_ = size;
    return packet;
  }
}

void L2Framer::finish() noexcept {
  window_.consume(release_);
  release_ = 0;
  const std::span<const std::uint8_t> rest = window_.view();
  if (!rest.empty()) {
    if (rest.size() >= 4 && std::equal(rest.begin(), rest.begin() + 4, std::begin(l2::kMagic))) {
      ++counters_.truncated;
      window_.clear();
    } else {
      skip(rest.size());
    }
  }
  window_.clear();
}

// ---------------------------------------------------------------------------------------------
// MAVLink v2 (L1)

std::optional<MavlinkMessageInfo> mavlink_message_info(std::uint32_t msgid) noexcept {
  // LEN and CRC_EXTRA of the messages in the L1 SDK's SysMavlink dialect (reference §8).
  static constexpr MavlinkMessageInfo kMessages[] = {
      {13, 38, 62},    // RET_LIDAR_VERSION
      {16, 246, 74},   // RET_LIDAR_DISTANCE_DATA_PACKET
      {17, 209, 99},   // RET_LIDAR_AUXILIARY_DATA_PACKET
      {18, 5, 12},     // RET_LIDAR_TIME_SYNC_DATA
      {19, 42, 110},   // RET_IMU_ATTITUDE_DATA_PACKET
  };
  for (const auto& m : kMessages) {
    if (m.msgid == msgid) return m;
  }
  return std::nullopt;
}

// Largest frame: header, 255 B payload, CRC, signature; the window holds many.
MavlinkFramer::MavlinkFramer() : window_(4096) {}

std::size_t MavlinkFramer::feed(std::span<const std::uint8_t> bytes) noexcept {
  window_.consume(release_);
  release_ = 0;
  return window_.append(bytes);
}

void MavlinkFramer::skip(std::size_t n) noexcept {
  if (n == 0) return;
  if (in_sync_) ++counters_.resyncs;
  in_sync_ = false;
  counters_.skipped_bytes += n;
  window_.consume(n);
}

namespace {
// Whether a plausible frame of a known message starts inside `bytes` (after its first byte).
bool contains_known_header(std::span<const std::uint8_t> bytes) {
  for (std::size_t i = 1; i + MavlinkFramer::kHeaderSize <= bytes.size(); ++i) {
    if (bytes[i] != std::uint8_t{MavlinkFramer::kStx}) continue;
    const std::uint32_t msgid = static_cast<std::uint32_t>(bytes[i + 7]) |
                                (static_cast<std::uint32_t>(bytes[i + 8]) << 8) |
                                (static_cast<std::uint32_t>(bytes[i + 9]) << 16);
    const auto info = mavlink_message_info(msgid);
    if (info && bytes[i + 1] <= info->length) return true;
  }
  return false;
}
}  // namespace

std::optional<MavlinkMessage> MavlinkFramer::next() noexcept {
  window_.consume(release_);
  release_ = 0;
  const std::uint8_t stx[1] = {std::uint8_t{kStx}};
  for (;;) {
    std::span<const std::uint8_t> bytes = window_.view();
    const std::size_t start = find_marker(bytes, stx);
    if (start > 0) {
      skip(start);
      bytes = window_.view();
    }
    if (bytes.size() < kHeaderSize) return std::nullopt;

    const std::size_t len = bytes[1];
    const auto incompat = bytes[2];
    const std::uint32_t msgid = static_cast<std::uint32_t>(bytes[7]) |
                                (static_cast<std::uint32_t>(bytes[8]) << 8) |
                                (static_cast<std::uint32_t>(bytes[9]) << 16);
    if ((incompat & ~0x01U) != 0) {  // only the "signed" flag is defined
      ++counters_.wrong_header;
      skip(1);
      continue;
    }
    const std::optional<MavlinkMessageInfo> info = mavlink_message_info(msgid);
    if (!info) {
      // Without its CRC_EXTRA a frame cannot be checked, so it is not trusted to be one either.
      ++counters_.unknown;
      skip(1);
      continue;
    }
    const std::size_t total = kHeaderSize + len + 2 + ((incompat & 0x01U) ? kSignatureSize : 0);
    if (bytes.size() < total) return std::nullopt;

    Crc16Mcrf4xx crc;
    crc.add(bytes.subspan(1, kHeaderSize - 1 + len));
    crc.add(info->crc_extra);
    if (crc.value() != le::u16(bytes, kHeaderSize + len)) {
      if (contains_known_header(bytes.first(total))) {
        ++counters_.truncated;
      } else {
        ++counters_.bad_crc;
      }
      skip(1);
      continue;
    }
    // A longer payload than we know carries extension fields of a newer dialect: ignore them.
    const std::size_t copied = std::min<std::size_t>(len, info->length);
    std::memcpy(payload_.data(), bytes.data() + kHeaderSize, copied);
    std::memset(payload_.data() + copied, 0, info->length - copied);

    MavlinkMessage message;
    message.msgid = msgid;
    message.seq = bytes[4];
    message.sysid = bytes[5];
    message.compid = bytes[6];
    message.payload = std::span<const std::uint8_t>(payload_.data(), info->length);
    ++counters_.packets;
    in_sync_ = true;
    release_ = total;
    return message;
  }
}

void MavlinkFramer::finish() noexcept {
  window_.consume(release_);
  release_ = 0;
  const std::span<const std::uint8_t> rest = window_.view();
  if (!rest.empty()) {
    if (rest[0] == std::uint8_t{kStx}) {
      ++counters_.truncated;
    } else {
      skip(rest.size());
    }
  }
  window_.clear();
}

}  // namespace sim::unitree
