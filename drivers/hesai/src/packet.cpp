// SPDX-License-Identifier: Apache-2.0
// Byte layouts (docs/hesai.md; read from tier4/nebula's packet structs and Hesai's SDKs): Pandar64,
// Pandar40P, XT32/XT16 (protocol 6.1), QT64 (protocol 3.1), QT128 (protocol 3.2) and XT32M
// (protocol 6.1 with 6 blocks).
#include "sim/hesai/packet.hpp"

#include <array>

#include "crc32_mpeg2.hpp"

namespace sim::hesai {
namespace {

// Channel firing offsets in ns relative to the block (reference §2, §3; nebula's tables).
constexpr std::array<std::int32_t, 64> pandar64_channel_ns{
    -23180, -21876, -20572, -19268, -17964, -16660, -11444, -46796, -7532,  -36956, -50732,
    -54668, -40892, -44828, -31052, -34988, -48764, -52700, -38924, -42860, -29084, -33020,
    -46796, -25148, -36956, -50732, -27116, -40892, -44828, -31052, -34988, -48764, -25148,
    -38924, -42860, -29084, -33020, -52700, -6228,  -54668, -15356, -27116, -10140, -23180,
    -4924,  -21876, -14052, -17964, -8836,  -19268, -3620,  -20572, -12748, -16660, -7532,
    -11444, -6228,  -15356, -10140, -4924,  -3620,  -14052, -8836,  -12748};

constexpr std::array<std::int32_t, 40> pandar40p_channel_ns{
    -42220, -28470, -16040, -3620,  -45490, -31740, -47460, -54670, -20620, -33710,
    -40910, -8190,  -20620, -27160, -50730, -8190,  -14740, -36980, -45490, -52700,
    -23890, -31740, -38950, -11470, -18650, -25190, -48760, -6230,  -12770, -35010,
    -21920, -9500,  -43520, -29770, -17350, -4920,  -42220, -28470, -16040, -3620};

// QT64: 10 µs + Hesai's firing-time table. Index 55 is 129600: nebula's 12960 is a typo
// (reference §5; GenSDK and the SDK 2 file agree on 119.6 + 10 µs).
constexpr std::array<std::int32_t, 64> pandar_qt64_channel_ns{
    12310,  14370,  16430,  18490,  20540,  22600,  24660,  26710,  29160,  31220,  33280,
    35340,  37390,  39450,  41500,  43560,  46610,  48670,  50730,  52780,  54840,  56900,
    58950,  61010,  63450,  65520,  67580,  69630,  71690,  73740,  75800,  77860,  80900,
    82970,  85020,  87080,  89140,  91190,  93250,  95300,  97750,  99820,  101870, 103930,
    105980, 108040, 110100, 112150, 115200, 117260, 119320, 121380, 123430, 125490, 127540,
    129600, 132050, 134110, 136170, 138220, 140280, 142340, 144390, 146450};

// QT128: channel firing times in ns after the block time for its two firing loops (nebula
// pandar_qt128.hpp). A 0 marks a channel that does not fire in that loop: 0–31 are dark in
// the first loop, 32–63 in the second.
constexpr std::array<std::int32_t, 128> pandar_qt128_loop1_ns{
    0,     0,     0,     0,     0,     0,     0,     0,     0,      0,     0,     0,     0,
    0,     0,     0,     0,     0,     0,     0,     0,     0,      0,     0,     0,     0,
    0,     0,     0,     0,     0,     0,     27656, 53000, 2312,   78344, 81512, 5480,  56168,
    30824, 33992, 59336, 8648,  84680, 87848, 11816, 62504, 37160,  40328, 65672, 14984, 91016,
    94184, 18152, 68840, 43496, 46664, 72008, 21320, 97352, 100520, 24488, 75176, 49832, 1456,
    77488, 26800, 52144, 55312, 29968, 80656, 4624,  7792,  83824,  33136, 58480, 61648, 36304,
    86992, 10960, 14128, 90160, 39472, 64816, 67984, 42640, 93328,  17296, 20464, 96496, 45808,
    71152, 74320, 48976, 99664, 23632, 25944, 51288, 600,   76632,  79800, 3768,  54456, 29112,
    32280, 57624, 6936,  82968, 86136, 10104, 60792, 35448, 38616,  63960, 13272, 89304, 92472,
    16440, 67128, 41784, 44952, 70296, 19608, 95640, 98808, 22776,  73464, 48120};
constexpr std::array<std::int32_t, 128> pandar_qt128_loop2_ns{
    2312,  78344, 27656, 53000, 56168,  30824, 81512, 5480,  8648,  84680, 33992, 59336, 62504,
    37160, 87848, 11816, 14984, 91016,  40328, 65672, 68840, 43496, 94184, 18152, 21320, 97352,
    46664, 72008, 75176, 49832, 100520, 24488, 0,     0,     0,     0,     0,     0,     0,
    0,     0,     0,     0,     0,      0,     0,     0,     0,     0,     0,     0,     0,
    0,     0,     0,     0,     0,      0,     0,     0,     0,     0,     0,     0,     600,
    76632, 25944, 51288, 54456, 29112,  79800, 3768,  6936,  82968, 32280, 57624, 60792, 35448,
    86136, 10104, 13272, 89304, 38616,  63960, 67128, 41784, 92472, 16440, 19608, 95640, 44952,
    70296, 73464, 48120, 98808, 22776,  26800, 52144, 1456,  77488, 80656, 4624,  55312, 29968,
    33136, 58480, 7792,  83824, 86992,  10960, 61648, 36304, 39472, 64816, 14128, 90160, 93328,
    17296, 67984, 42640, 45808, 71152,  20464, 96496, 99664, 23632, 74320, 48976};

using lidar::le16;
using lidar::le32;

// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's algorithm): no timegm,
// no time zone, no locale, safe on the hot path.
std::int64_t days_from_civil(int y, unsigned m, unsigned d) noexcept {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return std::int64_t{era} * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

bool leap(int y) noexcept { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

// UTC from the six date bytes Y M D h m s plus the µs field. The year byte counts from 1900
// on Pandar64/XT/QT firmware (120 = 2020) and from 2000 on Pandar40P firmware (17 = 2017);
// both fit "below 70 means 20xx". A date with month and day 0 is accepted and read as
// 1970-01-01 (plus the time of day) rather than dropping every packet of a sensor that has no
// time source yet.
bool utc_time_ns(const std::uint8_t* t, std::uint32_t micros, std::int64_t& out) noexcept {
  if (micros >= 1'000'000) return false;
  const unsigned hour = t[3], minute = t[4], second = t[5];
  if (hour > 23 || minute > 59 || second > 60) return false;
  std::int64_t days = 0;
  if (!(t[1] == 0 && t[2] == 0)) {
    const int year = t[0] < 70 ? 2000 + t[0] : 1900 + t[0];
    const unsigned month = t[1], day = t[2];
    constexpr std::array<unsigned, 12> month_days{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (month < 1 || month > 12 || day < 1) return false;
    const unsigned last_day = month_days[month - 1] + (month == 2 && leap(year) ? 1 : 0);
    if (day > last_day) return false;
    days = days_from_civil(year, month, day);
  }
  const std::int64_t seconds = days * 86400 + hour * 3600 + minute * 60 + second;
  out = seconds * 1'000'000'000 + std::int64_t{micros} * 1000;
  return true;
}

// Protocol 6.1 (XT): a year byte of 0 means bytes 2..5 hold big-endian Unix seconds.
bool xt_time_ns(const std::uint8_t* t, std::uint32_t micros, std::int64_t& out) noexcept {
  if (t[0] != 0) return utc_time_ns(t, micros, out);
  if (micros >= 1'000'000) return false;
  const std::uint32_t seconds = (std::uint32_t{t[2]} << 24) | (std::uint32_t{t[3]} << 16) |
                                (std::uint32_t{t[4]} << 8) | std::uint32_t{t[5]};
  out = std::int64_t{seconds} * 1'000'000'000 + std::int64_t{micros} * 1000;
  return true;
}

PacketError size_error(std::span<const std::uint8_t> payload, Model model) noexcept {
  const auto other = detect_model(payload);
  if (other && *other != model) return PacketError::wrong_model;
  return payload.size() < info(model).payload_size ? PacketError::too_short
                                                   : PacketError::bad_size;
}

// Where a model keeps each field Packet::parse reads (docs/hesai.md): the models differ in
// offsets far more than in what they send, so one table entry per model and one reader for
// all, rather than one parser per model.
struct PacketLayout {
  std::uint16_t first_block;   // offset of block 0 (after the header; the Pandar40P has none)
  std::uint16_t block_stride;  // bytes per block
  std::uint8_t azimuth;        // offset of the block azimuth inside a block
  std::uint8_t units;          // offset of channel 0's unit inside a block
  std::uint8_t unit_size;      // distance u16, reflectivity, and on 4-byte units one more byte
  std::uint8_t distance_unit;  // header byte holding the distance unit in mm; 0: none (4 mm)
  std::uint16_t tail;          // offset of the tail; the fields below are relative to it
  std::uint8_t rpm;
  std::uint8_t micros;
  std::uint8_t return_mode;
  std::uint8_t date;           // six bytes Y M D h m s
  std::uint8_t sequence;       // the UDP sequence, when the packet carries one
  bool unix_seconds_date;      // protocol 6.1: a year byte of 0 means Unix seconds (xt_time_ns)
};

constexpr PacketLayout layout_of(Model model) noexcept {
  // Columns: first block, block stride, azimuth, units, unit size, distance unit | tail, rpm,
  // µs, return mode, date, sequence, Unix-seconds date.
  switch (model) {
    case Model::pandar64:  // header 8 | 6 blocks of azimuth 2 + 64 units of 3 | tail
      return {8, 2 + 64 * 3, 0, 2, 3, 5, 8 + 6 * 194, 8, 10, 14, 16, 22, false};
    case Model::pandar40p:  // 10 blocks of marker 2 + azimuth 2 + 40 units of 3 | tail
      return {0, 4 + 40 * 3, 2, 4, 3, 0, 10 * 124, 8, 10, 14, 16, 22, false};
    case Model::pandar_xt32:  // header 12 | 8 blocks of azimuth 2 + 32 units of 4 | tail
      return {12, 2 + 32 * 4, 0, 2, 4, 9, 12 + 8 * 130, 11, 19, 10, 13, 24, true};
    case Model::pandar_xt16:  // header 12 | 8 blocks of azimuth 2 + 16 units of 4 | tail
      return {12, 2 + 16 * 4, 0, 2, 4, 9, 12 + 8 * 66, 11, 19, 10, 13, 24, true};
    case Model::pandar_xt32m:  // header 12 | 6 blocks of azimuth 2 + 32 units of 4 | tail
      return {12, 2 + 32 * 4, 0, 2, 4, 9, 12 + 6 * 130, 11, 19, 10, 13, 24, true};
    case Model::pandar_qt64:  // header 12 | 4 blocks of azimuth 2 + 64 units of 4 | tail
      return {12, 2 + 64 * 4, 0, 2, 4, 9, 12 + 4 * 258, 10, 12, 16, 18, 24, false};
    // Header 12 | 2 blocks of azimuth 2 + 128 units of 4 | body CRC 4 | functional safety 17
    // | tail 34 | optional signature 32.
    case Model::pandar_qt128:
      return {12, 2 + 128 * 4, 0, 2, 4, 9, 12 + 2 * 514 + 4 + 17, 13, 21, 12, 15, 26, false};
  }
  return {};
}

// QT128 sections around the tail: the blocks end at 1040, the body CRC follows, then the
// functional-safety section; the tail's mode flag names the firing loop of a multi-return packet.
constexpr std::size_t qt128_blocks_end = 12 + 2 * (2 + 128 * 4);
constexpr std::size_t qt128_safety = qt128_blocks_end + 4;
constexpr std::size_t qt128_mode_flag = 5;  // in the tail
static_assert(layout_of(Model::pandar_qt128).tail == qt128_safety + 17);

// Protocol version (major, minor) in header bytes 2 and 3 of the models whose header has one.
std::array<std::uint8_t, 2> protocol_version(Model model) noexcept {
  switch (model) {
    case Model::pandar_xt32:
    case Model::pandar_xt16:
    case Model::pandar_xt32m: return {6, 1};
    case Model::pandar_qt64: return {3, 1};
    case Model::pandar_qt128: return {3, 2};
    case Model::pandar64:
    case Model::pandar40p: break;
  }
  return {0, 0};
}

// The start-of-packet marker and the header's fixed bytes. The Pandar40P has no header: each of
// its blocks starts with a marker instead. The Pandar64's header has its laser and block count
// in bytes 2 and 3; the others have their protocol version there and the counts in 6 and 7.
PacketError check_header(const std::uint8_t* p, Model model, const ModelInfo& m,
                         const PacketLayout& layout) noexcept {
  if (model == Model::pandar40p) {
    for (unsigned b = 0; b < m.blocks_per_packet; ++b) {
      const std::uint8_t* block = p + b * layout.block_stride;
      if (block[0] != 0xFF || block[1] != 0xEE) return PacketError::bad_marker;
    }
    return PacketError::none;
  }
  if (p[0] != 0xEE || p[1] != 0xFF) return PacketError::bad_marker;
  if (model == Model::pandar64) {
    return p[2] == 64 && p[3] == 6 ? PacketError::none : PacketError::bad_header;
  }
  const auto version = protocol_version(model);
  const bool fixed_bytes_match = p[2] == version[0] && p[3] == version[1] &&
                                 p[6] == m.channels && p[7] == m.blocks_per_packet;
  return fixed_bytes_match ? PacketError::none : PacketError::bad_header;
}

// Whether the packet carries its UDP sequence: the XT says so in a header flag, the QT128
// always does, the others in the long form of their payload.
bool carries_sequence(const std::uint8_t* p, Model model, bool long_payload) noexcept {
  switch (model) {
    case Model::pandar_xt32:
    case Model::pandar_xt16:
    case Model::pandar_xt32m: return (p[11] & 0x01) != 0;
    case Model::pandar_qt128: return true;
    case Model::pandar64:
    case Model::pandar40p:
    case Model::pandar_qt64: return long_payload;
  }
  return false;
}

// QT128 CRCs (stored little-endian after the bytes they cover): body = the blocks, safety =
// the functional-safety section after its version byte, tail = the tail before its CRC.
bool qt128_crcs_match(const std::uint8_t* p) noexcept {
  constexpr std::size_t tail = layout_of(Model::pandar_qt128).tail;
  return detail::crc32_mpeg2(p + 12, qt128_blocks_end - 12) == le32(p + qt128_blocks_end) &&
         detail::crc32_mpeg2(p + qt128_safety + 1, 12) == le32(p + qt128_safety + 13) &&
         detail::crc32_mpeg2(p + tail, 30) == le32(p + tail + 30);
}

// Azimuths: in range, equal inside a return group, and moving forward by a small step from
// group to group (real sensors step 0.18°–0.6°; 10° leaves room for any rpm). This also
// guarantees that one packet crosses the cut azimuth at most once.
bool azimuths_step_forward(const Packet& pk) noexcept {
  constexpr unsigned max_group_step = 1000;  // 0.01°
  const unsigned returns = pk.returns();
  for (unsigned b = 0; b < pk.blocks(); ++b) {
    const std::uint16_t az = pk.azimuth(b);
    if (az >= 36000) return false;
    if (b % returns != 0) {
      if (az != pk.azimuth(b - b % returns)) return false;
    } else if (b > 0) {
      const unsigned step = (az + 36000u - pk.azimuth(b - returns)) % 36000u;
      if (step == 0 || step > max_group_step) return false;
    }
  }
  return true;
}

FunctionalSafety read_safety(const std::uint8_t* fs) noexcept {
  FunctionalSafety out;
  const unsigned state = fs[1] >> 5;
  out.state = state <= 4 ? static_cast<LidarState>(state) : LidarState::output_untrusted;
  const unsigned type = (fs[1] >> 3) & 0x3;
  out.fault_type = type <= 2 ? static_cast<FaultCodeType>(type) : FaultCodeType::current;
  out.rolling_counter = fs[1] & 0x7;
  out.total_fault_codes = static_cast<std::uint8_t>(fs[2] >> 4);
  out.fault_code_id = fs[2] & 0xF;
  out.fault_code = le16(fs + 3);
  return out;
}

}  // namespace

unsigned returns_of(ReturnMode mode) noexcept {
  switch (mode) {
    case ReturnMode::first:
    case ReturnMode::second:
    case ReturnMode::strongest:
    case ReturnMode::last: return 1;
    case ReturnMode::dual_last_strongest:
    case ReturnMode::dual_first_second:
    case ReturnMode::dual_first_last:
    case ReturnMode::dual_first_strongest:
    case ReturnMode::dual_strongest_second: return 2;
    case ReturnMode::triple: return 3;
  }
  return 0;
}

const char* to_string(PacketError error) noexcept {
  switch (error) {
    case PacketError::none: return "packet decoded";
    case PacketError::too_short: return "packet shorter than the model's packet (cut short)";
    case PacketError::bad_size: return "packet length is not one the model sends";
    case PacketError::bad_marker: return "packet lacks the Hesai start-of-packet/block bytes";
    case PacketError::wrong_model: return "packet comes from another Hesai model than configured";
    case PacketError::bad_header: return "packet header has the wrong laser count, block count or protocol version";
    case PacketError::bad_return_mode: return "packet has an unknown or impossible return mode";
    case PacketError::bad_distance_unit: return "packet has a distance unit of 0";
    case PacketError::bad_azimuth: return "packet has an impossible block azimuth";
    case PacketError::bad_time: return "packet has an impossible UTC date or time";
    case PacketError::bad_crc: return "packet's CRC does not match its bytes (corrupted on the way)";
  }
  return "unknown packet error";
}

const char* to_string(LidarState state) noexcept {
  switch (state) {
    case LidarState::initialization: return "initialization";
    case LidarState::normal: return "normal";
    case LidarState::warning: return "warning";
    case LidarState::performance_degradation: return "performance degradation";
    case LidarState::output_untrusted: return "output untrusted";
  }
  return "unknown";
}

PacketError Packet::parse(std::span<const std::uint8_t> payload, Model model,
                          Packet& out) noexcept {
  const ModelInfo& m = info(model);
  const std::size_t n = payload.size();
  if (n != m.payload_size && n != m.long_payload_size) return size_error(payload, model);
  const std::uint8_t* p = payload.data();
  const PacketLayout layout = layout_of(model);

  if (const PacketError e = check_header(p, model, m, layout); e != PacketError::none) return e;
  // Checked before any field is believed: a corrupted packet is dropped as such.
  if (model == Model::pandar_qt128 && !qt128_crcs_match(p)) return PacketError::bad_crc;

  // The payload has the model's length, so every offset of its layout lies inside it.
  Packet pk;
  pk.data_ = p;
  pk.model_ = model;
  pk.blocks_ = static_cast<std::uint8_t>(m.blocks_per_packet);
  pk.channels_ = static_cast<std::uint8_t>(m.channels);
  pk.first_block_ = layout.first_block;
  pk.block_stride_ = layout.block_stride;
  pk.az_offset_ = layout.azimuth;
  pk.units_offset_ = layout.units;
  pk.unit_size_ = layout.unit_size;

  const std::uint8_t* tail = p + layout.tail;
  pk.rpm_ = le16(tail + layout.rpm);
  pk.has_sequence_ = carries_sequence(p, model, n == m.long_payload_size);
  if (pk.has_sequence_) pk.sequence_ = le32(tail + layout.sequence);
  if (model == Model::pandar_qt128) {
    pk.mode_flag_ = tail[qt128_mode_flag];
    pk.has_safety_ = true;
    pk.safety_ = read_safety(p + qt128_safety);
  }

  std::uint8_t distance_unit_mm = 4;  // the Pandar40P's, which does not send it
  if (layout.distance_unit != 0) distance_unit_mm = p[layout.distance_unit];
  if (distance_unit_mm == 0) return PacketError::bad_distance_unit;
  pk.distance_unit_m_ = static_cast<float>(distance_unit_mm) * 0.001f;

  pk.return_mode_ = static_cast<ReturnMode>(tail[layout.return_mode]);
  const unsigned returns = returns_of(pk.return_mode_);
  if (returns == 0 || pk.blocks_ % returns != 0) return PacketError::bad_return_mode;
  pk.returns_ = static_cast<std::uint8_t>(returns);

  if (!azimuths_step_forward(pk)) return PacketError::bad_azimuth;

  const std::uint8_t* date = tail + layout.date;
  const std::uint32_t micros = le32(tail + layout.micros);
  const bool time_ok = layout.unix_seconds_date ? xt_time_ns(date, micros, pk.time_ns_)
                                                : utc_time_ns(date, micros, pk.time_ns_);
  if (!time_ok) return PacketError::bad_time;

  out = pk;
  return PacketError::none;
}

std::int32_t Packet::block_offset_ns(unsigned block) const noexcept {
  // Blocks of one return group fire together; k counts groups.
  const std::int32_t r = returns_;
  const std::int32_t b = static_cast<std::int32_t>(block);
  switch (model_) {
    case Model::pandar64: return -42580 - 55560 * ((6 - b - 1) / r);
    case Model::pandar40p: return -28580 - 55560 * ((10 - b - 1) / r);
    case Model::pandar_xt32:
    case Model::pandar_xt16: return -50000 * ((8 - b - 1) / r);
    case Model::pandar_qt64: return 25710 + (500000 * (b / r)) / 3;
    // Firings 111.11 µs (0.4° at 600 rpm) apart, the second block's azimuth being the later
    // one. nebula writes 9000 + 111110·(2 − b − 1)/n, which puts block 0 last; the azimuths
    // say otherwise, so SIM follows them (unverified on a live sensor).
    case Model::pandar_qt128: return 9000 + 111110 * (b / r);
    // nebula uses (8 − b − 1) here, the XT32's block count, for a 6-block packet; SIM counts
    // the XT32M's own 6 blocks so the last firing group is at the packet time, as on the XT32.
    case Model::pandar_xt32m: return -50000 * ((6 - b - 1) / r);
  }
  return 0;
}

unsigned Packet::firing_loop(unsigned block) const noexcept {
  if (model_ != Model::pandar_qt128) return 0;
  // Single return: the two blocks are consecutive firings, first loop then second. Multi
  // return: one firing, whose loop the tail's mode flag names (bit 0 set = first loop).
  if (returns_ == 1) return block % 2;
  return (mode_flag_ & 0x01) != 0 ? 0 : 1;
}

std::int32_t Packet::channel_offset_ns(Model model, unsigned channel, unsigned loop) noexcept {
  const std::int32_t c = static_cast<std::int32_t>(channel);
  switch (model) {
    case Model::pandar64: return channel < 64 ? pandar64_channel_ns[channel] : 0;
    case Model::pandar40p: return channel < 40 ? pandar40p_channel_ns[channel] : 0;
    // nebula: 5632 (block base) + 368 + 1512·ch; the block base is folded in here so the
    // channel term equals Hesai's firing-time file (6 µs + 1.512 µs·ch).
    case Model::pandar_xt32: return 6000 + 1512 * c;
    case Model::pandar_xt16: return 6000 + 3024 * c;
    case Model::pandar_qt64: return channel < 64 ? pandar_qt64_channel_ns[channel] : 0;
    case Model::pandar_qt128:
      if (channel >= 128) return 0;
      return loop == 0 ? pandar_qt128_loop1_ns[channel] : pandar_qt128_loop2_ns[channel];
    // nebula: 5632 + 368 + 2888·(ch mod 16): channels c and c + 16 fire together.
    case Model::pandar_xt32m: return 6000 + 2888 * (c % 16);
  }
  return 0;
}

std::int32_t Packet::firing_offset_ns(unsigned block, unsigned channel) const noexcept {
  return block_offset_ns(block) + channel_offset_ns(model_, channel, firing_loop(block));
}

}  // namespace sim::hesai
