// SPDX-License-Identifier: Apache-2.0
// Ouster lidar and IMU packets (firmware 2.x/3.x): the pixel profiles, the packet layout a
// sensor's metadata implies, and a checked view over one UDP payload. No I/O, no allocation.
//
// A lidar packet holds `columns_per_packet` columns (one firing of all H beams each). LEGACY
// packets have no packet header, a 16-byte column header (timestamp u64 ns, measurement_id u16,
// frame_id u16, encoder u32), H 12-byte pixels and a u32 status (all ones = valid) per column.
// The other profiles have a 32-byte packet header (packet_type, frame_id, init_id, serial,
// alerts; FUSA: frame_id u32), 12-byte column headers (timestamp, measurement_id, status bit 0 =
// valid), H pixels of the profile's size, and a 32-byte footer. All little-endian.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sim/lidar/little_endian.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

// The pixel layouts ("udp_profile_lidar" in the metadata).
enum class Profile : std::uint8_t {
  legacy,                       // 12 B: RANGE 20 bits (mm), REFLECTIVITY, SIGNAL, NEAR_IR
  rng19_rfl8_sig16_nir16,       // 12 B: RANGE 19 bits + 5 flag bits, REFLECTIVITY, SIGNAL, NEAR_IR
  rng19_rfl8_sig16_nir16_dual,  // 16 B: two returns (RANGE, REFLECTIVITY, SIGNAL each), NEAR_IR
  rng15_rfl8_nir8,              // 4 B "low data rate": RANGE 15 bits × 8 mm, REFLECTIVITY, NIR × 16
  fusa_rng15_rfl8_nir8_dual,    // 8 B: two RNG15 returns, functional-safety packet header
};

inline constexpr unsigned profile_count = 5;

std::optional<Profile> parse_profile(std::string_view name) noexcept;
std::string_view to_string(Profile profile) noexcept;
// "LEGACY, RNG19_RFL8_SIG16_NIR16, …" for messages.
std::string_view profile_names() noexcept;
unsigned pixel_bytes(Profile profile) noexcept;
unsigned returns_of(Profile profile) noexcept;
bool has_signal(Profile profile) noexcept;  // the RNG15 profiles carry no SIGNAL field

// Every field a pixel may carry, decoded. Fields the profile lacks are 0.
struct Pixel {
  std::uint32_t range_mm = 0;   // 0: no return
  std::uint32_t range2_mm = 0;  // second return (dual profiles)
  std::uint16_t signal = 0;
  std::uint16_t signal2 = 0;
  std::uint16_t near_ir = 0;
  std::uint8_t reflectivity = 0;
  std::uint8_t reflectivity2 = 0;
  std::uint8_t flags = 0;
  std::uint8_t flags2 = 0;
};

// Decodes one pixel of profile P from its bytes (pixel_bytes(P) of them). Bit positions are
// those of the firmware user manual's "Lidar Data Format" tables.
template <Profile P>
inline Pixel decode_pixel_as(const std::uint8_t* b) noexcept {
  auto u16 = [b](unsigned at) { return lidar::le16(b + at); };
  auto u32 = [b](unsigned at) { return lidar::le32(b + at); };
  Pixel px;
  if constexpr (P == Profile::legacy || P == Profile::rng19_rfl8_sig16_nir16) {
    const std::uint32_t w0 = u32(0);
    if constexpr (P == Profile::legacy) {
      px.range_mm = w0 & 0xfffffu;
      px.flags = static_cast<std::uint8_t>(w0 >> 28);
    } else {
      px.range_mm = w0 & 0x7ffffu;
      px.flags = static_cast<std::uint8_t>((w0 >> 19) & 0x1fu);
    }
    px.reflectivity = b[4];
    px.signal = u16(6);
    px.near_ir = u16(8);
  } else if constexpr (P == Profile::rng19_rfl8_sig16_nir16_dual) {
    const std::uint32_t w0 = u32(0);
    const std::uint32_t w1 = u32(4);
    px.range_mm = w0 & 0x7ffffu;
    px.flags = static_cast<std::uint8_t>((w0 >> 19) & 0x1fu);
    px.reflectivity = b[3];
    px.range2_mm = w1 & 0x7ffffu;
    px.flags2 = static_cast<std::uint8_t>((w1 >> 19) & 0x1fu);
    px.reflectivity2 = b[7];
    px.signal = u16(8);
    px.signal2 = u16(10);
    px.near_ir = u16(12);
  } else {  // RNG15: range in units of 8 mm, near-IR in units of 16
    const std::uint16_t w0 = u16(0);
    px.range_mm = std::uint32_t{w0 & 0x7fffu} << 3;
    px.flags = static_cast<std::uint8_t>(w0 >> 15);
    px.reflectivity = b[2];
    px.near_ir = static_cast<std::uint16_t>(b[3] << 4);
    if constexpr (P == Profile::fusa_rng15_rfl8_nir8_dual) {
      const std::uint16_t w2 = u16(4);
      px.range2_mm = std::uint32_t{w2 & 0x7fffu} << 3;
      px.flags2 = static_cast<std::uint8_t>(w2 >> 15);
      px.reflectivity2 = b[6];
    }
  }
  return px;
}

// The same for a profile known at run time.
Pixel decode_pixel(Profile profile, const std::uint8_t* bytes) noexcept;

// A column's header.
struct Column {
  std::uint64_t timestamp_ns = 0;  // the sensor's clock (PTP/GPS when synchronised, else since boot)
  std::uint16_t measurement_id = 0;  // column index in the frame, 0 … columns_per_frame − 1
  std::uint32_t status = 0;        // LEGACY: u32 (all ones = valid); others: u16, bit 0 = valid
  std::uint32_t encoder = 0;       // LEGACY only
  bool valid = false;
};

// The layout of a sensor's lidar packets, from its metadata.
struct PacketFormat {
  Profile profile = Profile::legacy;
  bool fusa_header = false;       // 32-bit frame_id header (the FUSA profile)
  unsigned pixels_per_column = 0;  // H, beams: 16, 32, 64 or 128
  unsigned columns_per_packet = 0;  // sensors send 16; at most max_columns_per_packet
  unsigned columns_per_frame = 0;  // W: 512, 1024, 2048 or 4096
  std::size_t header_bytes = 0;
  std::size_t column_header_bytes = 0;
  std::size_t column_bytes = 0;
  std::size_t footer_bytes = 0;
  std::size_t packet_bytes = 0;

  // More than any Ouster sensor sends, with room to spare (the decoder's per-packet arrays).
  static constexpr unsigned max_columns_per_packet = 64;

  // Fails (one sentence) for sizes no sensor uses or a packet above 65,507 bytes (UDP's limit).
  static Expected<PacketFormat> create(Profile profile, unsigned pixels_per_column,
                                       unsigned columns_per_packet, unsigned columns_per_frame,
                                       bool fusa_header = false);
  // "RNG19_RFL8_SIG16_NIR16_DUAL, 32 beams, 16 columns per packet (8448-byte packets)".
  std::string describe() const;
};

// Why a payload is not a usable lidar packet of the format. Counted, never fatal.
enum class PacketError : std::uint8_t {
  none,
  wrong_size,          // not the format's size: another profile, beam count or columns per
                       // packet (metadata of another sensor or mode), or a cut datagram
  not_lidar,           // packet_type is not 1 (lidar)
  bad_measurement_id,  // a column index beyond columns_per_frame: wrong metadata or damage
  mixed_frame_ids,     // LEGACY: the columns of one packet disagree on the frame
  init_id_mismatch,    // the sensor restarted or reconfigured since the metadata was taken
};
inline constexpr unsigned packet_error_count = 6;
const char* to_string(PacketError error) noexcept;

// A checked view over one lidar payload; valid while the payload is.
class LidarPacket {
 public:
  // `expected_init_id` (non-LEGACY): the metadata's initialization_id; 0 skips the check.
  static PacketError parse(std::span<const std::uint8_t> payload, const PacketFormat& format,
                           LidarPacket& out, std::uint32_t expected_init_id = 0) noexcept;

  std::uint32_t frame_id() const noexcept { return frame_id_; }
  std::uint32_t init_id() const noexcept { return init_id_; }      // 0 for LEGACY
  std::uint64_t serial() const noexcept { return serial_; }        // 0 for LEGACY
  std::uint16_t packet_type() const noexcept { return packet_type_; }
  unsigned columns() const noexcept { return format_->columns_per_packet; }
  Column column(unsigned index) const noexcept;
  // The raw bytes of pixel `row` of column `index`; decode with decode_pixel().
  const std::uint8_t* pixel_bytes(unsigned index, unsigned row) const noexcept {
    return column_start(index) + format_->column_header_bytes + std::size_t{row} * pixel_size_;
  }
  Pixel pixel(unsigned index, unsigned row) const noexcept {
    return decode_pixel(format_->profile, pixel_bytes(index, row));
  }
  const PacketFormat& format() const noexcept { return *format_; }

 private:
  const std::uint8_t* column_start(unsigned index) const noexcept {
    return data_ + format_->header_bytes + std::size_t{index} * format_->column_bytes;
  }

  const std::uint8_t* data_ = nullptr;
  const PacketFormat* format_ = nullptr;
  std::size_t pixel_size_ = 0;
  std::uint32_t frame_id_ = 0;
  std::uint32_t init_id_ = 0;
  std::uint64_t serial_ = 0;
  std::uint16_t packet_type_ = 0;
};

// What a payload that did not fit says about the metadata, in one sentence: e.g. "packets are
// 8448 bytes but the metadata describes LEGACY, 32 beams, 16 columns per packet (6464-byte
// packets): the metadata is not this sensor's or its mode changed; give the sensor's own".
std::string describe_mismatch(std::size_t payload_bytes, const PacketFormat& format);

// Whether a payload looks like an Ouster lidar packet without its metadata: its size fits a
// profile with 16, 32, 64 or 128 beams and 16 columns per packet (or 8, 4, 2, 1), and every
// column's measurement_id (and the packet type) is plausible. For telling the family of a
// capture; decoding still needs the metadata.
std::optional<PacketFormat> guess_format(std::span<const std::uint8_t> payload) noexcept;

// The LEGACY IMU packet (48 bytes, port 7503).
inline constexpr std::size_t imu_packet_bytes = 48;

struct ImuPacket {
  std::uint64_t system_ns = 0;  // when the packet was sent
  std::uint64_t accel_ns = 0;   // when the accelerometer was read
  std::uint64_t gyro_ns = 0;
  float acceleration_g[3] = {0, 0, 0};     // in g
  float angular_velocity_dps[3] = {0, 0, 0};  // in degrees/s
};

// nullopt for a payload that is not a 48-byte IMU packet with finite readings.
std::optional<ImuPacket> parse_imu(std::span<const std::uint8_t> payload) noexcept;

}  // namespace sim::ouster
