// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/ptc.hpp"

#include <cstdio>
#include <string>

namespace sim::hesai::ptc {
namespace {

Error bad_answer(std::string message) {
  return Error{ErrorCode::invalid_argument, std::move(message)};
}

// A NUL-padded text field, printable ASCII only, without surrounding spaces.
std::string text_field(std::span<const std::uint8_t> bytes) {
  std::string text;
  for (const std::uint8_t byte : bytes) {
    if (byte == 0) break;
    if (byte >= 0x20 && byte < 0x7F) text += static_cast<char>(byte);
  }
  const auto first = text.find_first_not_of(' ');
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

}  // namespace

std::array<std::uint8_t, header_size> request(std::uint8_t command) noexcept {
  return {0x47, 0x74, command, 0, 0, 0, 0, 0};
}

Expected<ResponseHeader> parse_header(std::span<const std::uint8_t> bytes, std::uint8_t command) {
  if (bytes.size() < header_size) {
    return bad_answer("the answer is " + std::to_string(bytes.size()) +
                      " bytes, shorter than a PTC header (8); the sensor closed the connection "
                      "early");
  }
  if (bytes[0] != 0x47 || bytes[1] != 0x74) {
    char first[16];
    std::snprintf(first, sizeof first, "%02X %02X", bytes[0], bytes[1]);
    return bad_answer(std::string("the answer is not Hesai PTC (it starts with ") + first +
                      ", not 47 74); check that --sensor-ip is the LiDAR and the port is its PTC "
                      "port");
  }
  if (bytes[2] != command) {
    return bad_answer("the answer is for PTC command " + std::to_string(bytes[2]) +
                      ", not the " + std::to_string(command) + " asked for");
  }
  if (bytes[3] != 0) {
    return bad_answer("the sensor refused the request: PTC return code " +
                      std::to_string(bytes[3]) + " (its meaning is in the sensor's PTC manual)");
  }
  ResponseHeader header;
  header.command = bytes[2];
  header.payload_size = (std::uint32_t{bytes[4]} << 24) | (std::uint32_t{bytes[5]} << 16) |
                        (std::uint32_t{bytes[6]} << 8) | std::uint32_t{bytes[7]};
  if (header.payload_size > max_payload_size) {
    return bad_answer("the answer announces " + std::to_string(header.payload_size) +
                      " bytes, more than any calibration file; it is not a calibration");
  }
  return header;
}

Expected<std::span<const std::uint8_t>> parse_response(std::span<const std::uint8_t> bytes,
                                                       std::uint8_t command) {
  auto header = parse_header(bytes, command);
  if (!header) return header.error();
  const std::size_t expected = header_size + header->payload_size;
  if (bytes.size() != expected) {
    return bad_answer("the answer holds " + std::to_string(bytes.size() - header_size) +
                      " payload bytes but announces " + std::to_string(header->payload_size));
  }
  return bytes.subspan(header_size);
}

Expected<Inventory> parse_inventory(std::span<const std::uint8_t> payload) {
  if (payload.size() < inventory_size) {
    return bad_answer("the inventory answer is " + std::to_string(payload.size()) +
                      " bytes, shorter than the " + std::to_string(inventory_size) +
                      " of a Hesai inventory");
  }
  Inventory inventory;
  inventory.serial = text_field(payload.subspan(0, 18));
  inventory.manufactured = text_field(payload.subspan(18, 16));
  // mac: 6 bytes at 34
  inventory.software = text_field(payload.subspan(40, 16));
  inventory.hardware = text_field(payload.subspan(56, 16));
  inventory.control_firmware = text_field(payload.subspan(72, 16));
  inventory.sensor_firmware = text_field(payload.subspan(88, 16));
  // angle_offset: u16 at 104
  inventory.model_code = payload[106];
  inventory.lines = payload[108];
  return inventory;
}

}  // namespace sim::hesai::ptc
