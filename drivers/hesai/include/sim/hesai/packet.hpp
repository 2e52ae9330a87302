// SPDX-License-Identifier: Apache-2.0
// One Hesai point-cloud UDP payload, validated once and then read through a non-owning view.
// Packet::parse checks the length, the markers, the header counts, every block azimuth, the
// return mode, the distance unit, the UTC date and, where the packet carries them, its CRCs
// before anything reads the body, so the accessors need no further checks and cannot read
// outside the payload.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "sim/hesai/model.hpp"
#include "sim/lidar/little_endian.hpp"

namespace sim::hesai {

// Tail byte "return mode" (nebula hesai_packet.hpp; reference §1).
enum class ReturnMode : std::uint8_t {
  first = 0x33,
  second = 0x34,
  strongest = 0x37,
  last = 0x38,
  dual_last_strongest = 0x39,
  dual_first_second = 0x3a,
  dual_first_last = 0x3b,
  dual_first_strongest = 0x3c,
  triple = 0x3d,
  dual_strongest_second = 0x3e,
};

// 1, 2 or 3; 0 for a byte that is no return mode.
unsigned returns_of(ReturnMode mode) noexcept;

// Why a payload was not decoded. Drivers count these per reason.
enum class PacketError : std::uint8_t {
  none = 0,
  too_short,          // shorter than the smallest packet of the model
  bad_size,           // a length the model never sends
  bad_marker,         // start-of-packet / start-of-block bytes missing
  wrong_model,        // a well-formed packet of another Hesai model
  bad_header,         // laser/block count or protocol version not the model's
  bad_return_mode,    // unknown return-mode byte, or returns that do not divide the blocks
  bad_distance_unit,  // distance unit 0
  bad_azimuth,        // azimuth ≥ 360°, return group disagreeing, or azimuth going backwards
  bad_time,           // UTC date fields that are no date
  bad_crc,            // body, functional-safety or tail CRC does not match (QT128)
};
inline constexpr std::size_t packet_error_count = 11;

// One sentence for logs and status lines ("packet shorter than the model's packet size").
const char* to_string(PacketError error) noexcept;

// The QT128's functional-safety section (hesai-qt128-xt32m.md §6.3; nebula
// functional_safety.hpp), refreshed by the sensor every 5 ms.
enum class LidarState : std::uint8_t {
  initialization = 0,
  normal = 1,
  warning = 2,
  performance_degradation = 3,
  output_untrusted = 4,
};
enum class FaultCodeType : std::uint8_t { none = 0, current = 1, past = 2 };

struct FunctionalSafety {
  LidarState state = LidarState::normal;   // values above 4 are reported as output_untrusted
  FaultCodeType fault_type = FaultCodeType::none;
  std::uint8_t total_fault_codes = 0;      // faults the sensor is cycling through
  std::uint8_t fault_code_id = 0;          // which of them this packet reports
  std::uint16_t fault_code = 0;            // Hesai's code (see the sensor's manual)
  std::uint8_t rolling_counter = 0;
};

// "normal", "performance degradation", … for status lines.
const char* to_string(LidarState state) noexcept;

class Packet {
 public:
  Packet() = default;

  // Validates `payload` as a packet of `model` and points `out` at it (the bytes must outlive
  // `out`). Returns PacketError::none on success; `out` is unchanged otherwise.
  static PacketError parse(std::span<const std::uint8_t> payload, Model model,
                           Packet& out) noexcept;

  Model model() const noexcept { return model_; }
  ReturnMode return_mode() const noexcept { return return_mode_; }
  unsigned returns() const noexcept { return returns_; }
  unsigned blocks() const noexcept { return blocks_; }
  unsigned channels() const noexcept { return channels_; }
  float distance_unit_m() const noexcept { return distance_unit_m_; }
  std::uint16_t motor_rpm() const noexcept { return rpm_; }

  // The functional-safety section, for models that send one (QT128).
  std::optional<FunctionalSafety> functional_safety() const noexcept {
    return has_safety_ ? std::optional<FunctionalSafety>(safety_) : std::nullopt;
  }

  // Sensor time of the packet, ns since the Unix epoch (UTC fields + µs field).
  std::int64_t time_ns() const noexcept { return time_ns_; }
  // The UDP sequence number, when the sensor sends one.
  std::optional<std::uint32_t> sequence() const noexcept {
    return has_sequence_ ? std::optional<std::uint32_t>(sequence_) : std::nullopt;
  }

  // Block azimuth in 0.01° (0…35999). All blocks of one return group share it.
  std::uint16_t azimuth(unsigned block) const noexcept { return lidar::le16(block_at(block) + az_offset_); }
  std::uint16_t raw_distance(unsigned block, unsigned channel) const noexcept {
    return lidar::le16(unit_at(block, channel));
  }
  std::uint8_t reflectivity(unsigned block, unsigned channel) const noexcept {
    return unit_at(block, channel)[2];
  }
  // The block's channel units back to back, unit_size() bytes each (distance u16 little
  // endian, reflectivity, and on 4-byte units a confidence or reserved byte): for decoders
  // that read a whole block in one loop with the unit size as a constant.
  const std::uint8_t* units(unsigned block) const noexcept { return block_at(block) + units_offset_; }
  unsigned unit_size() const noexcept { return unit_size_; }

  // Firing time of (block, channel) relative to time_ns(), in ns, from the model's built-in
  // tables (Pandar64/40P/XT negative, QT positive). Depends on the return mode: blocks of one
  // return group fire together.
  std::int32_t firing_offset_ns(unsigned block, unsigned channel) const noexcept;
  // The block term alone (firing_offset_ns = block term + channel term).
  std::int32_t block_offset_ns(unsigned block) const noexcept;
  // The QT128 alternates two firing loops with different channel timings (and 32 dark
  // channels each): which one fired this block, 0 or 1. Always 0 for the other models.
  unsigned firing_loop(unsigned block) const noexcept;
  static std::int32_t channel_offset_ns(Model model, unsigned channel,
                                        unsigned loop = 0) noexcept;

 private:
  const std::uint8_t* block_at(unsigned block) const noexcept {
    return data_ + first_block_ + std::size_t{block} * block_stride_;
  }
  const std::uint8_t* unit_at(unsigned block, unsigned channel) const noexcept {
    return block_at(block) + units_offset_ + std::size_t{channel} * unit_size_;
  }

  const std::uint8_t* data_ = nullptr;
  std::int64_t time_ns_ = 0;
  float distance_unit_m_ = 0.004f;
  std::uint32_t sequence_ = 0;
  bool has_sequence_ = false;
  Model model_ = Model::pandar64;
  ReturnMode return_mode_ = ReturnMode::last;
  std::uint8_t returns_ = 1;
  std::uint8_t blocks_ = 0;
  std::uint8_t channels_ = 0;
  std::uint8_t unit_size_ = 3;
  std::uint8_t az_offset_ = 0;
  std::uint8_t units_offset_ = 2;
  std::uint16_t first_block_ = 0;
  std::uint16_t block_stride_ = 0;
  std::uint16_t rpm_ = 0;
  std::uint8_t mode_flag_ = 0;  // QT128 tail: bit 0 selects the firing loop of a multi-return packet
  bool has_safety_ = false;
  FunctionalSafety safety_{};
};

}  // namespace sim::hesai
