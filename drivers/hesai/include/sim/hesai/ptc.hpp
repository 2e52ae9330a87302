// SPDX-License-Identifier: Apache-2.0
// Hesai's PTC protocol (TCP port 9347), the bytes only: the request for one command and the
// checks of the sensor's answer. No I/O here; the TCP client is sim/hesai/ptc_client.hpp.
//
// Request and response share an 8-byte header (Hesai SDK 2, ptc_1_0_parser.h):
//   0x47 0x74 | command | return code (0 = ok) | payload length, u32 big-endian
// followed by the payload. Command 0x05 answers with the angle-correction file: the same CSV
// text the calibration files hold (the QT128, XT and Pandar64/40P serve CSV).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "sim/result.hpp"

namespace sim::hesai::ptc {

inline constexpr std::uint16_t default_port = 9347;
inline constexpr std::uint8_t get_calibration = 0x05;
// Answers with the unit's inventory: serial number, versions, model code (layout below).
inline constexpr std::uint8_t get_inventory = 0x07;
inline constexpr std::size_t header_size = 8;
// No calibration file is anywhere near this; a larger announced payload is not one.
inline constexpr std::uint32_t max_payload_size = 1 << 20;

std::array<std::uint8_t, header_size> request(std::uint8_t command) noexcept;

struct ResponseHeader {
  std::uint8_t command = 0;
  std::uint32_t payload_size = 0;
};

// Checks the first header_size bytes of an answer to `command`: Hesai's identifier, the same
// command, return code 0 and a payload size up to max_payload_size. Each failure is one
// sentence ("the sensor refused the request: PTC return code 3 (…)").
Expected<ResponseHeader> parse_header(std::span<const std::uint8_t> bytes, std::uint8_t command);

// A whole answer (header and exactly its payload): the payload, viewing `bytes`.
Expected<std::span<const std::uint8_t>> parse_response(std::span<const std::uint8_t> bytes,
                                                       std::uint8_t command);

// The inventory answer (Hesai's PTC manual; nebula's HesaiInventory): NUL-padded text fields
// sn[18] date_of_manufacture[16] mac[6] sw_ver[16] hw_ver[16] control_fw_ver[16]
// sensor_fw_ver[16], then angle_offset u16, model u8, motor_type u8, num_of_lines u8, 11 reserved:
// 120 bytes. Longer answers (newer firmware) are read for these fields.
inline constexpr std::size_t inventory_size = 120;
struct Inventory {
  std::string serial;
  std::string manufactured;
  std::string software;          // sw_ver
  std::string hardware;          // hw_ver
  std::string control_firmware;  // control_fw_ver
  std::string sensor_firmware;   // sensor_fw_ver
  std::uint8_t model_code = 0;
  std::uint8_t lines = 0;
};

// The inventory in a get_inventory payload; text fields keep their printable ASCII only (a
// hostile answer cannot smuggle control bytes into a stream's description). One sentence when
// the payload is too short.
Expected<Inventory> parse_inventory(std::span<const std::uint8_t> payload);

}  // namespace sim::hesai::ptc
