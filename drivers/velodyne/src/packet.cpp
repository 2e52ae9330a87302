// SPDX-License-Identifier: Apache-2.0
// Data packet: 12 blocks × (flag u16, azimuth u16 in 0.01°, 32 × (distance u16, reflectivity
// u8)), timestamp u32 at 1200, return mode at 1204, product ID at 1205. Position packet:
// timestamp at 198, PPS state at 202, NMEA sentence from 206.
#include "sim/velodyne/packet.hpp"

#include <array>
#include <cstring>
#include <ctime>

namespace sim::velodyne {
namespace {

// Block flags as read little-endian: FF EE reads 0xEEFF.
constexpr std::array<std::uint16_t, 4> bank_flags{0xEEFF, 0xDDFF, 0xCCFF, 0xBBFF};

// The flag block `block` must carry for `model` (dual: VLS-128 pairs are one bank).
std::uint16_t expected_flag(Model model, unsigned block, bool dual) noexcept {
  switch (model) {
    case Model::vls128: return bank_flags[(dual ? block / 2 : block) % 4];
    case Model::hdl64e: return bank_flags[block % 2];
    default: return bank_flags[0];
  }
}

// The HDL-64E names no return mode. An S3 in dual return sends three firings per packet, each as
// four blocks (upper and lower strongest, upper and lower last) with the firing's azimuth; in
// single return six firings of two blocks (upper, lower). So each group's two upper blocks and
// two lower blocks at one azimuth, with a motor that turns between the groups (a stopped motor
// is no data anyone decodes), mean dual.
bool hdl64e_dual_layout(const std::uint8_t* data) noexcept {
  const auto azimuth = [data](unsigned block) { return Packet::read_u16(data + block * block_size + 2); };
  for (unsigned group = 0; group < blocks_per_packet; group += 4) {
    if (azimuth(group) != azimuth(group + 2) || azimuth(group + 1) != azimuth(group + 3)) return false;
  }
  return azimuth(0) != azimuth(4) || azimuth(4) != azimuth(8);
}

}  // namespace

const char* to_string(ReturnMode mode) noexcept {
  switch (mode) {
    case ReturnMode::strongest: return "strongest";
    case ReturnMode::last: return "last";
    case ReturnMode::dual: return "dual";
  }
  return "?";
}

const char* to_string(PacketError error) noexcept {
  switch (error) {
    case PacketError::none: return "no error";
    case PacketError::bad_size: return "a datagram that is not a 1206-byte Velodyne data packet";
    case PacketError::wrong_model: return "a packet of another model than the stream's";
    case PacketError::bad_flag: return "a block that does not start with the flag the model sends there";
    case PacketError::bad_azimuth: return "a block azimuth of 360 degrees or more";
    case PacketError::bad_return_mode: return "a return-mode byte that is none of 0x37, 0x38, 0x39";
  }
  return "unknown packet error";
}

PacketError Packet::parse(std::span<const std::uint8_t> payload, Model model, Packet& out) noexcept {
  if (payload.size() != packet_size) return PacketError::bad_size;
  const std::uint8_t* data = payload.data();
  if (const auto detected = detect_model(payload); detected && *detected != model) {
    return PacketError::wrong_model;
  }
  // The HDL-64E sends no product ID (bytes 1204-1205 are its rotating status), nor does an
  // HDL-32E before firmware 2.2.20 (both bytes 0: strongest); every other model names itself.
  const bool unnamed_hdl32e = model == Model::hdl32e && is_unnamed_hdl32e(payload);
  if (model != Model::hdl64e && !unnamed_hdl32e && data[product_id_offset] != info(model).product_id) {
    return PacketError::wrong_model;
  }
  ReturnMode mode = ReturnMode::strongest;
  if (model != Model::hdl64e && !unnamed_hdl32e) {
    const std::uint8_t byte = data[return_mode_offset];
    if (byte < 0x37 || byte > 0x39) return PacketError::bad_return_mode;
    mode = static_cast<ReturnMode>(byte);
  } else if (hdl64e_dual_layout(data)) {
    mode = ReturnMode::dual;
  }
  const bool dual = mode == ReturnMode::dual;
  const unsigned blocks = (model == Model::vls128 && dual) ? 8 : blocks_per_packet;
  for (unsigned b = 0; b < blocks; ++b) {
    const std::uint8_t* block = data + b * block_size;
    if (read_u16(block) != expected_flag(model, b, dual)) return PacketError::bad_flag;
    if (read_u16(block + 2) >= 36000) return PacketError::bad_azimuth;
  }
  out.data_ = data;
  out.model_ = model;
  out.return_mode_ = mode;
  out.blocks_ = static_cast<std::uint8_t>(blocks);
  return PacketError::none;
}

unsigned Packet::laser(unsigned block, unsigned unit) const noexcept {
  switch (model_) {
    case Model::vlp16:
    case Model::puck_hires: return unit % 16;
    case Model::vls128: return (dual() ? (block / 2) % 4 : block % 4) * 32 + unit;
    case Model::hdl64e: return (block % 2) * 32 + unit;
    default: return unit;
  }
}

unsigned Packet::sequence(unsigned block, unsigned unit) const noexcept {
  const unsigned slot = dual() ? block / 2 : block;  // the two blocks of a pair fire together
  switch (model_) {
    case Model::vlp16:
    case Model::puck_hires: return slot * 2 + unit / 16;
    case Model::vls128: return dual() ? 0 : block / 4;
    case Model::hdl64e: return slot / 2;  // upper and lower block (dual: both returns of each)
    default: return slot;
  }
}

const char* to_string(PpsState state) noexcept {
  switch (state) {
    case PpsState::absent: return "absent";
    case PpsState::synchronizing: return "synchronizing";
    case PpsState::locked: return "locked";
    case PpsState::error: return "error";
    case PpsState::unknown: return "unknown";
    case PpsState::invalid: return "invalid";
  }
  return "unknown";
}

const char* to_string(NmeaStatus status) noexcept {
  switch (status) {
    case NmeaStatus::none: return "none";
    case NmeaStatus::unreadable: return "unreadable";
    case NmeaStatus::no_fix: return "no fix";
    case NmeaStatus::fix: return "fix";
  }
  return "unreadable";
}

namespace {

int hex_digit(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool two_digits(std::string_view s, std::size_t at, int& out) noexcept {
  if (at + 2 > s.size()) return false;
  const char a = s[at];
  const char b = s[at + 1];
  if (a < '0' || a > '9' || b < '0' || b > '9') return false;
  out = (a - '0') * 10 + (b - '0');
  return true;
}

// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's algorithm).
std::int64_t days_from_civil(int y, unsigned m, unsigned d) noexcept {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return std::int64_t{era} * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

// The sentence's body between '$' and '*' when its checksum is good.
std::optional<std::string_view> checked_body(std::string_view sentence) noexcept {
  const std::size_t star = sentence.rfind('*');
  if (sentence.size() < 7 || sentence[0] != '$' || star == std::string_view::npos || star + 3 > sentence.size()) {
    return std::nullopt;
  }
  unsigned sum = 0;
  for (std::size_t i = 1; i < star; ++i) sum ^= static_cast<unsigned char>(sentence[i]);
  const int hi = hex_digit(sentence[star + 1]);
  const int lo = hex_digit(sentence[star + 2]);
  if (hi < 0 || lo < 0 || static_cast<unsigned>(hi * 16 + lo) != sum) return std::nullopt;
  return sentence.substr(1, star - 1);
}

using NmeaFields = std::array<std::string_view, 10>;

// The first fields of "GPRMC,a,b,…"; how many there are (at most 10).
std::size_t split_fields(std::string_view body, NmeaFields& fields) noexcept {
  std::size_t count = 0;
  while (count < fields.size()) {
    const std::size_t comma = body.find(',');
    fields[count++] = body.substr(0, comma);
    if (comma == std::string_view::npos) break;
    body.remove_prefix(comma + 1);
  }
  return count;
}

// "hhmmss[.ss]" as hours, minutes and seconds, each in range.
bool time_of_day(std::string_view text, int& hh, int& mi, int& ss) noexcept {
  return two_digits(text, 0, hh) && two_digits(text, 2, mi) && two_digits(text, 4, ss) && hh <= 23 &&
         mi <= 59 && ss <= 60;
}

// "$GPRMC,hhmmss[.ss],A,lat,N,lon,E,speed,course,ddmmyy,…": status and UTC.
void parse_rmc(const NmeaFields& fields, std::size_t count, PositionReport& report) noexcept {
  report.has_gprmc = true;
  if (count < 3) return;  // unreadable: no status
  report.gprmc_valid = fields[2] == "A";
  report.nmea = report.gprmc_valid ? NmeaStatus::fix : NmeaStatus::no_fix;
  int hh = 0, mi = 0, ss = 0, dd = 0, mo = 0, yy = 0;
  if (!time_of_day(fields[1], hh, mi, ss)) return;
  report.nmea_second_of_hour = mi * 60 + ss;
  if (count < 10 || !two_digits(fields[9], 0, dd) || !two_digits(fields[9], 2, mo) || !two_digits(fields[9], 4, yy)) {
    return;
  }
  if (dd < 1 || dd > 31 || mo < 1 || mo > 12) return;
  // Two-digit years: 80–99 are 1980–1999, the rest 2000–2079.
  const std::int64_t days = days_from_civil(yy >= 80 ? 1900 + yy : 2000 + yy, static_cast<unsigned>(mo), static_cast<unsigned>(dd));
  report.gprmc_utc_s = days * 86400 + hh * 3600 + mi * 60 + ss;
}

// "$GPGGA,hhmmss[.ss],lat,N,lon,E,quality,…": the fix quality (0 none) and the time of day.
void parse_gga(const NmeaFields& fields, std::size_t count, PositionReport& report) noexcept {
  if (count < 7 || fields[6].size() != 1 || fields[6][0] < '0' || fields[6][0] > '9') return;  // unreadable
  report.nmea = fields[6][0] == '0' ? NmeaStatus::no_fix : NmeaStatus::fix;
  int hh = 0, mi = 0, ss = 0;
  if (time_of_day(fields[1], hh, mi, ss)) report.nmea_second_of_hour = mi * 60 + ss;
}

void parse_nmea(std::string_view sentence, PositionReport& report) noexcept {
  if (sentence.empty()) return;  // NmeaStatus::none
  report.nmea = NmeaStatus::unreadable;
  const auto body = checked_body(sentence);
  if (!body || body->size() < 5) return;
  NmeaFields fields{};
  const std::size_t count = split_fields(*body, fields);
  // Any talker ("GP", "GN", …): the sentence type is the three letters after it.
  const std::string_view type = fields[0].size() == 5 ? fields[0].substr(2) : std::string_view();
  if (type == "RMC") parse_rmc(fields, count, report);
  if (type == "GGA") parse_gga(fields, count, report);
}

}  // namespace

std::optional<PositionReport> parse_position_packet(std::span<const std::uint8_t> payload,
                                                    std::optional<Model> model) noexcept {
  constexpr std::size_t nmea_offset = 206;
  if (payload.size() != 512 && payload.size() != 554) return std::nullopt;
  PositionReport report;
  report.timestamp_us = Packet::read_u32(payload.data() + 198);
  report.pps_byte = payload[202];
  if (model != Model::hdl32e && model != Model::hdl64e) {
    report.pps = report.pps_byte <= 3 ? static_cast<PpsState>(report.pps_byte) : PpsState::invalid;
  }
  const std::size_t room = payload.size() - nmea_offset;
  const auto* text = reinterpret_cast<const char*>(payload.data() + nmea_offset);
  std::size_t length = 0;
  while (length < room && length < 128 && text[length] != '\0' && text[length] != '\r' && text[length] != '\n') {
    ++length;
  }
  parse_nmea(std::string_view(text, length), report);
  return report;
}

}  // namespace sim::velodyne
