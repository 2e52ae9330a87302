// SPDX-License-Identifier: Apache-2.0
// One Velodyne data packet (UDP port 2368), validated once and then read through a non-owning
// view, and one position packet (port 8308: the sensor's GPRMC sentence and PPS state).
// Packet::parse checks the length, every block flag the model must send, every azimuth used
// and the return mode before anything reads the body, so the accessors need no further checks.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "sim/lidar/little_endian.hpp"
#include "sim/velodyne/model.hpp"

namespace sim::velodyne {

// Byte 1204. The HDL-64E uses bytes 1204–1205 for its rotating status instead: its packets
// read as dual when their block azimuths have the S3's dual-return layout (see
// Packet::return_index), as strongest otherwise.
enum class ReturnMode : std::uint8_t { strongest = 0x37, last = 0x38, dual = 0x39 };
const char* to_string(ReturnMode mode) noexcept;  // "strongest", "last", "dual"

// Why a payload was not decoded. Drivers count these per reason.
enum class PacketError : std::uint8_t {
  none = 0,
  bad_size,         // not the 1206 bytes of a data packet (truncated, another device)
  wrong_model,      // a Velodyne packet of another model (or another vendor's 1206 bytes)
  bad_flag,         // a block does not start with the flag the model sends there
  bad_azimuth,      // a block azimuth of 360° or more
  bad_return_mode,  // byte 1204 is no return mode
};
inline constexpr std::size_t packet_error_count = 6;

// One sentence for logs and status lines ("a block does not start with its FF EE flag").
const char* to_string(PacketError error) noexcept;

class Packet {
 public:
  Packet() = default;

  // Validates `payload` as a data packet of `model`; `out` views it (the bytes must outlive it).
  static PacketError parse(std::span<const std::uint8_t> payload, Model model, Packet& out) noexcept;

  Model model() const noexcept { return model_; }
  ReturnMode return_mode() const noexcept { return return_mode_; }
  bool dual() const noexcept { return return_mode_ == ReturnMode::dual; }
  // Blocks that carry data: 12, except the VLS-128 in dual return (8, the last 4 are empty).
  unsigned blocks() const noexcept { return blocks_; }
  // Microseconds past the top of the hour of the packet's first firing (byte 1200).
  std::uint32_t timestamp_us() const noexcept { return read_u32(data_ + timestamp_offset); }

  std::uint16_t flag(unsigned block) const noexcept { return read_u16(block_at(block)); }
  std::uint16_t azimuth(unsigned block) const noexcept { return read_u16(block_at(block) + 2); }
  std::uint16_t raw_distance(unsigned block, unsigned unit) const noexcept {
    return read_u16(block_at(block) + 4 + unit * 3);
  }
  std::uint8_t reflectivity(unsigned block, unsigned unit) const noexcept {
    return block_at(block)[4 + unit * 3 + 2];
  }
  // The block's 32 × (distance u16, reflectivity u8) bytes.
  const std::uint8_t* units(unsigned block) const noexcept { return block_at(block) + 4; }

  // Dual return: which return `block` holds, 0 for the last, 1 for the strongest (or the second
  // strongest when the strongest is the last), and the block with the other return of the same
  // firing. VLP-16/32C, HDL-32E, VLS-128: pairs (0|1, 2|3, …), the even block the last return.
  // HDL-64E S3: groups of four blocks of one firing, upper and lower strongest, then upper and
  // lower last.
  unsigned return_index(unsigned block) const noexcept {
    return model_ == Model::hdl64e ? ((block / 2) % 2 == 0 ? 1U : 0U) : block % 2;
  }
  unsigned partner(unsigned block) const noexcept { return model_ == Model::hdl64e ? block ^ 2U : block ^ 1U; }

  // The laser (calibration index) of `unit` in `block`: the VLS-128's bank flag (FF EE, DD, CC,
  // BB) adds 0, 32, 64 or 96, the HDL-64E's lower block (FF DD) 32, the VLP-16 holds two
  // sequences of 16 lasers per block.
  unsigned laser(unsigned block, unsigned unit) const noexcept;
  // Which firing sequence of the packet `block`/`unit` belongs to (0-based); the two blocks of a
  // dual-return pair share it.
  unsigned sequence(unsigned block, unsigned unit) const noexcept;

  // The packet's little-endian fields (sim/lidar/little_endian.hpp), by the names the replay
  // and tests read a timestamp with.
  static std::uint16_t read_u16(const std::uint8_t* p) noexcept { return lidar::le16(p); }
  static std::uint32_t read_u32(const std::uint8_t* p) noexcept { return lidar::le32(p); }

 private:
  const std::uint8_t* block_at(unsigned block) const noexcept { return data_ + block * block_size; }

  const std::uint8_t* data_ = nullptr;
  Model model_ = Model::vlp16;
  ReturnMode return_mode_ = ReturnMode::strongest;
  std::uint8_t blocks_ = blocks_per_packet;
};

// The PPS input's state as a position packet reports it (byte 202; VLP-16/32C, VLS-128).
// unknown: the model reports none (HDL-32E/64E: byte 202 is unused there); invalid: a byte
// outside 0–3 (a corrupt packet, or another device on the position port).
enum class PpsState : std::uint8_t { absent = 0, synchronizing = 1, locked = 2, error = 3, unknown = 4, invalid = 5 };
const char* to_string(PpsState state) noexcept;  // "absent", "synchronizing", "locked", "error", …

// The NMEA sentence a position packet carries (the sensor forwards its GNSS receiver's $GPRMC
// or, when so configured, $GPGGA).
enum class NmeaStatus : std::uint8_t {
  none,        // no sentence (no receiver connected)
  unreadable,  // text that is no $--RMC or $--GGA with a good checksum
  no_fix,      // RMC status 'V', or GGA fix quality 0
  fix,         // RMC status 'A', or GGA fix quality above 0
};
const char* to_string(NmeaStatus status) noexcept;  // "none", "unreadable", "no fix", "fix"

// What a position packet says about the sensor's clock.
struct PositionReport {
  std::uint32_t timestamp_us = 0;   // µs past the hour, as in data packets
  PpsState pps = PpsState::unknown;
  std::uint8_t pps_byte = 0;        // byte 202 as sent (for messages about an invalid one)
  NmeaStatus nmea = NmeaStatus::none;
  bool has_gprmc = false;           // a $GPRMC (or $GNRMC) sentence with a good checksum
  bool gprmc_valid = false;         // its status is 'A' (a GPS fix), not 'V'
  // UTC of the sentence, seconds since the Unix epoch, when it has a time and a date (RMC).
  std::optional<std::int64_t> gprmc_utc_s;
  // Minutes and seconds of the sentence's UTC, as seconds past the hour (RMC or GGA): what the
  // top-of-hour counter should agree with when PPS is locked.
  std::optional<std::int32_t> nmea_second_of_hour;
};

// Position packets are 512 bytes of UDP payload (554 on the wire; a 554-byte payload is taken
// too): the timestamp at 198, the PPS state at 202 and the NMEA sentence from 206 (up to 128
// bytes, NUL-terminated). `model`, when known, says whether byte 202 is a PPS state (not on the
// HDL-32E/64E). nullopt for anything else.
std::optional<PositionReport> parse_position_packet(std::span<const std::uint8_t> payload,
                                                    std::optional<Model> model = std::nullopt) noexcept;

}  // namespace sim::velodyne
