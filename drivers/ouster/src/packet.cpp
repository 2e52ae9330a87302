// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/packet.hpp"

#include <cmath>

namespace sim::ouster {
namespace {

using lidar::le16;
using lidar::le32;
using lidar::le64;
using lidar::le_uint;
using lidar::le_f32;

struct ProfileInfo {
  Profile profile;
  std::string_view name;
  unsigned bytes;
  unsigned returns;
  bool signal;
};

constexpr ProfileInfo profiles[profile_count] = {
    {Profile::legacy, "LEGACY", 12, 1, true},
    {Profile::rng19_rfl8_sig16_nir16, "RNG19_RFL8_SIG16_NIR16", 12, 1, true},
    {Profile::rng19_rfl8_sig16_nir16_dual, "RNG19_RFL8_SIG16_NIR16_DUAL", 16, 2, true},
    {Profile::rng15_rfl8_nir8, "RNG15_RFL8_NIR8", 4, 1, false},
    {Profile::fusa_rng15_rfl8_nir8_dual, "FUSA_RNG15_RFL8_NIR8_DUAL", 8, 2, false},
};

const ProfileInfo& info(Profile p) noexcept { return profiles[static_cast<unsigned>(p)]; }

// The largest UDP payload over IPv4.
constexpr std::size_t max_udp_payload = 65507;

}  // namespace

std::optional<Profile> parse_profile(std::string_view name) noexcept {
  for (const ProfileInfo& p : profiles) {
    if (p.name == name) return p.profile;
  }
  return std::nullopt;
}
std::string_view to_string(Profile profile) noexcept { return info(profile).name; }
std::string_view profile_names() noexcept {
  return "LEGACY, RNG19_RFL8_SIG16_NIR16, RNG19_RFL8_SIG16_NIR16_DUAL, RNG15_RFL8_NIR8, "
         "FUSA_RNG15_RFL8_NIR8_DUAL";
}
unsigned pixel_bytes(Profile profile) noexcept { return info(profile).bytes; }
unsigned returns_of(Profile profile) noexcept { return info(profile).returns; }
bool has_signal(Profile profile) noexcept { return info(profile).signal; }

Pixel decode_pixel(Profile profile, const std::uint8_t* b) noexcept {
  switch (profile) {
    case Profile::legacy: return decode_pixel_as<Profile::legacy>(b);
    case Profile::rng19_rfl8_sig16_nir16: return decode_pixel_as<Profile::rng19_rfl8_sig16_nir16>(b);
    case Profile::rng19_rfl8_sig16_nir16_dual:
      return decode_pixel_as<Profile::rng19_rfl8_sig16_nir16_dual>(b);
    case Profile::rng15_rfl8_nir8: return decode_pixel_as<Profile::rng15_rfl8_nir8>(b);
    case Profile::fusa_rng15_rfl8_nir8_dual:
      return decode_pixel_as<Profile::fusa_rng15_rfl8_nir8_dual>(b);
  }
  return {};
}

Expected<PacketFormat> PacketFormat::create(Profile profile, unsigned pixels_per_column,
                                            unsigned columns_per_packet,
                                            unsigned columns_per_frame, bool fusa_header) {
  auto invalid = [](std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; };
  if (pixels_per_column == 0 || pixels_per_column > 256) {
    return invalid("pixels_per_column " + std::to_string(pixels_per_column) +
                   " is not a beam count (Ouster sensors have 16, 32, 64 or 128)");
  }
  if (columns_per_frame == 0 || columns_per_frame > 4096) {
    return invalid("columns_per_frame " + std::to_string(columns_per_frame) +
                   " is not a lidar mode's (512, 1024, 2048 or 4096)");
  }
  if (columns_per_packet == 0 || columns_per_packet > columns_per_frame) {
    return invalid("columns_per_packet " + std::to_string(columns_per_packet) +
                   " does not fit a frame of " + std::to_string(columns_per_frame) + " columns");
  }
  if (columns_per_packet > max_columns_per_packet) {
    return invalid("columns_per_packet " + std::to_string(columns_per_packet) +
                   " is more than any Ouster sensor sends (at most " + std::to_string(max_columns_per_packet) + ")");
  }
  PacketFormat f;
  f.profile = profile;
  f.fusa_header = fusa_header || profile == Profile::fusa_rng15_rfl8_nir8_dual;
  f.pixels_per_column = pixels_per_column;
  f.columns_per_packet = columns_per_packet;
  f.columns_per_frame = columns_per_frame;
  const bool legacy = profile == Profile::legacy;
  f.header_bytes = legacy ? 0 : 32;
  f.footer_bytes = legacy ? 0 : 32;
  f.column_header_bytes = legacy ? 16 : 12;
  f.column_bytes = f.column_header_bytes + std::size_t{pixels_per_column} * pixel_bytes(profile) +
                   (legacy ? 4 : 0);
  f.packet_bytes = f.header_bytes + columns_per_packet * f.column_bytes + f.footer_bytes;
  if (f.packet_bytes > max_udp_payload) {
    return invalid(f.describe() + " would not fit a UDP datagram; check the metadata");
  }
  return f;
}

std::string PacketFormat::describe() const {
  return std::string(to_string(profile)) + ", " + std::to_string(pixels_per_column) + " beams, " +
         std::to_string(columns_per_packet) + " columns per packet (" +
         std::to_string(packet_bytes) + "-byte packets)";
}

const char* to_string(PacketError error) noexcept {
  switch (error) {
    case PacketError::none: return "none";
    case PacketError::wrong_size: return "wrong size";
    case PacketError::not_lidar: return "not a lidar packet";
    case PacketError::bad_measurement_id: return "bad measurement id";
    case PacketError::mixed_frame_ids: return "mixed frame ids";
    case PacketError::init_id_mismatch: return "init id mismatch";
  }
  return "unknown";
}

PacketError LidarPacket::parse(std::span<const std::uint8_t> payload, const PacketFormat& format,
                               LidarPacket& out, std::uint32_t expected_init_id) noexcept {
  if (payload.size() != format.packet_bytes) return PacketError::wrong_size;
  out.data_ = payload.data();
  out.format_ = &format;
  out.pixel_size_ = sim::ouster::pixel_bytes(format.profile);
  const std::uint8_t* p = payload.data();
  if (format.profile == Profile::legacy) {
    out.packet_type_ = 1;
    out.init_id_ = 0;
    out.serial_ = 0;
    out.frame_id_ = le16(p + 10);
    for (unsigned c = 1; c < format.columns_per_packet; ++c) {
      if (le16(out.column_start(c) + 10) != out.frame_id_) return PacketError::mixed_frame_ids;
    }
  } else if (format.fusa_header) {
    out.packet_type_ = p[0];
    out.init_id_ = static_cast<std::uint32_t>(le_uint(p + 1, 3));
    out.frame_id_ = le32(p + 4);
    out.serial_ = le_uint(p + 11, 5);
  } else {
    out.packet_type_ = le16(p);
    out.frame_id_ = le16(p + 2);
    out.init_id_ = static_cast<std::uint32_t>(le_uint(p + 4, 3));
    out.serial_ = le_uint(p + 7, 5);
  }
  if (out.packet_type_ != 1) return PacketError::not_lidar;
  for (unsigned c = 0; c < format.columns_per_packet; ++c) {
    if (le16(out.column_start(c) + 8) >= format.columns_per_frame) {
      return PacketError::bad_measurement_id;
    }
  }
  if (expected_init_id != 0 && format.profile != Profile::legacy && out.init_id_ != expected_init_id) {
    return PacketError::init_id_mismatch;
  }
  return PacketError::none;
}

Column LidarPacket::column(unsigned index) const noexcept {
  const std::uint8_t* c = column_start(index);
  Column col;
  col.timestamp_ns = le64(c);
  col.measurement_id = le16(c + 8);
  if (format_->profile == Profile::legacy) {
    col.encoder = le32(c + 12);
    col.status = le32(c + format_->column_bytes - 4);
    col.valid = col.status == 0xffffffffu;
  } else {
    col.status = le16(c + 10);
    col.valid = (col.status & 1u) != 0;
  }
  return col;
}

std::string describe_mismatch(std::size_t payload_bytes, const PacketFormat& format) {
  std::string text = "lidar packets of " + std::to_string(payload_bytes) +
                     " bytes arrive but the metadata describes " + format.describe() +
                     ": the metadata is not this sensor's or its mode or profile changed";
  // Name the likely difference when one profile or beam count explains the size.
  for (const ProfileInfo& p : profiles) {
    for (unsigned beams : {16u, 32u, 64u, 128u}) {
      auto other = PacketFormat::create(p.profile, beams, format.columns_per_packet,
                                        format.columns_per_frame);
      if (other && other->packet_bytes == payload_bytes) {
        return text + " (the packets fit " + std::string(p.name) + " with " +
               std::to_string(beams) + " beams); give the sensor's current metadata";
      }
    }
  }
  return text + "; give the sensor's current metadata";
}

std::optional<PacketFormat> guess_format(std::span<const std::uint8_t> payload) noexcept {
  for (const ProfileInfo& p : profiles) {
    for (unsigned beams : {16u, 32u, 64u, 128u}) {
      for (unsigned per_packet : {16u, 8u, 4u, 2u, 1u}) {
        // 4096 columns: the largest lidar mode bounds every measurement_id.
        auto format = PacketFormat::create(p.profile, beams, per_packet, 4096);
        if (!format || format->packet_bytes != payload.size()) continue;
        LidarPacket packet;
        if (LidarPacket::parse(payload, *format, packet) != PacketError::none) continue;
        // Consecutive columns: a packet holds neighbouring measurements.
        bool consecutive = true;
        for (unsigned c = 1; c < per_packet && consecutive; ++c) {
          consecutive = packet.column(c).measurement_id == packet.column(c - 1).measurement_id + 1;
        }
        if (consecutive) return *format;
      }
    }
  }
  return std::nullopt;
}

std::optional<ImuPacket> parse_imu(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != imu_packet_bytes) return std::nullopt;
  const std::uint8_t* p = payload.data();
  ImuPacket imu;
  imu.system_ns = le64(p);
  imu.accel_ns = le64(p + 8);
  imu.gyro_ns = le64(p + 16);
  for (unsigned i = 0; i < 3; ++i) {
    imu.acceleration_g[i] = le_f32(p + 24 + 4 * i);
    imu.angular_velocity_dps[i] = le_f32(p + 36 + 4 * i);
    if (!std::isfinite(imu.acceleration_g[i]) || !std::isfinite(imu.angular_velocity_dps[i])) {
      return std::nullopt;
    }
  }
  return imu;
}

}  // namespace sim::ouster
