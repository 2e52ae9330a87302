// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/frame_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace sim::ouster {
namespace {

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

std::uint32_t to_mm(float metres) {
  return static_cast<std::uint32_t>(std::lround(static_cast<double>(metres) * 1000.0));
}

// The largest UDP payload over IPv4: room for any packet that waits for the next span.
constexpr std::size_t max_packet_bytes = 65507;

}  // namespace

Expected<FrameAssembler> FrameAssembler::create(const Metadata& metadata, AssemblerOptions options) {
  if (!std::isfinite(options.min_range_m) || !std::isfinite(options.max_range_m) ||
      options.min_range_m < 0 || options.max_range_m < 0 ||
      (options.max_range_m > 0 && options.max_range_m <= options.min_range_m)) {
    return invalid("the range limits must be finite, not negative, and the maximum above the minimum");
  }
  if (metadata.beam_altitude_deg.size() != metadata.beams() ||
      metadata.beam_azimuth_deg.size() != metadata.beams() ||
      metadata.pixel_shift_by_row.size() != metadata.beams()) {
    return invalid("the metadata's beam tables do not have one entry per beam");
  }
  if (metadata.format.columns_per_packet > max_columns_per_packet) {
    return invalid("the metadata's " + std::to_string(metadata.format.columns_per_packet) +
                   " columns per packet are more than any Ouster sensor sends (" +
                   std::to_string(max_columns_per_packet) + ")");
  }
  const Profile profile = metadata.format.profile;
  if (!has_signal(profile) && options.intensity == IntensityField::signal) {
    return invalid("the " + std::string(to_string(profile)) +
                   " profile carries no signal channel; choose reflectivity or near-ir as intensity");
  }
  FrameAssembler assembler(metadata, options);
  assembler.build_lookup_table();
  return assembler;
}

FrameAssembler::FrameAssembler(const Metadata& metadata, AssemblerOptions options)
    : metadata_(metadata), options_(options) {
  beams_ = metadata.beams();
  columns_ = metadata.columns();
  returns_ = options.first_return_only ? 1 : returns_of(metadata.format.profile);
  min_range_mm_ = to_mm(options.min_range_m);
  max_range_mm_ = options.max_range_m > 0 ? to_mm(options.max_range_m)
                                          : std::numeric_limits<std::uint32_t>::max();
  intensity_ = options.intensity;
  if (intensity_ == IntensityField::automatic) {
    intensity_ = has_signal(metadata.format.profile) ? IntensityField::signal : IntensityField::reflectivity;
  }
  received_.assign(columns_, 0);
  pending_.resize(max_packet_bytes);
}

// The firmware manual's "Lidar Range to XYZ": for column m (encoder angle θe = 2π(1 − m/W)) and
// beam u (azimuth offset θa = −2π·az/360, altitude φ = 2π·alt/360), the pixel of range r lies
// at (r − n)·d + o in the lidar frame, d = (cos(θe+θa)·cos φ, sin(θe+θa)·cos φ, sin φ) and
// o = (T03·cos θe, T03·sin θe, T23) with T the beam-to-lidar transform (T03 = n on FW 2.x).
// In the sensor frame that is (r − n)·R·d + (R·o + t): a direction per pixel and an origin per
// column, so decoding a point is three multiply-adds and the table stays small (12 B a pixel).
void FrameAssembler::build_lookup_table() {
  direction_.resize(3 * std::size_t{columns_} * beams_);
  column_origin_.resize(3 * std::size_t{columns_});
  row_shift_.resize(beams_);
  const auto& m = metadata_;
  const double t03 = m.beam_to_lidar[3];
  const double t23 = m.beam_to_lidar[11];
  const auto& s = m.lidar_to_sensor;
  constexpr double pi = std::numbers::pi;
  for (unsigned col = 0; col < columns_; ++col) {
    const double encoder = 2 * pi * (1.0 - static_cast<double>(col) / columns_);
    const double o[3] = {t03 * std::cos(encoder), t03 * std::sin(encoder), t23};
    for (unsigned row = 0; row < 3; ++row) {
      const double* r = &s[4 * row];
      column_origin_[3 * col + row] = static_cast<float>((r[0] * o[0] + r[1] * o[1] + r[2] * o[2] + r[3]) / 1000.0);
    }
    for (unsigned u = 0; u < beams_; ++u) {
      const double azimuth = encoder - 2 * pi * m.beam_azimuth_deg[u] / 360.0;
      const double altitude = 2 * pi * m.beam_altitude_deg[u] / 360.0;
      const double d[3] = {std::cos(azimuth) * std::cos(altitude),
                           std::sin(azimuth) * std::cos(altitude), std::sin(altitude)};
      const std::size_t at = std::size_t{u} * columns_ + col;
      for (unsigned row = 0; row < 3; ++row) {
        const double* r = &s[4 * row];
        direction_[3 * at + row] = static_cast<float>((r[0] * d[0] + r[1] * d[1] + r[2] * d[2]) / 1000.0);
      }
    }
  }
  const long w = columns_;
  for (unsigned u = 0; u < beams_; ++u) {
    row_shift_[u] = static_cast<unsigned>((m.pixel_shift_by_row[u] % w + w) % w);
  }
  beam_origin_mm_ = static_cast<float>(m.lidar_origin_to_beam_origin_mm);
}

std::size_t FrameAssembler::max_points() const noexcept {
  return std::size_t{beams_} * columns_ * returns_;
}

void FrameAssembler::set_output(std::span<LidarPoint> output) noexcept {
  output_ = output;
  attached_ = true;
  // Mid-frame, the points decoded so far went elsewhere: what follows is a partial frame.
  if (open_) open_ = false;
  if (pending_size_ != 0) {
    LidarPacket packet;
    const std::span<const std::uint8_t> bytes(pending_.data(), pending_size_);
    pending_size_ = 0;
    if (LidarPacket::parse(bytes, metadata_.format, packet, metadata_.init_id) == PacketError::none) {
      begin(packet, pending_host_ns_);
      decode(packet);
    }
  }
}

void FrameAssembler::reset() noexcept {
  open_ = false;
  pending_size_ = 0;
}

void FrameAssembler::begin(const LidarPacket& packet, std::int64_t host_ns) noexcept {
  open_ = true;
  frame_id_ = packet.frame_id();
  whole_ = false;
  for (unsigned c = 0; c < packet.columns(); ++c) {
    if (packet.column(c).measurement_id == metadata_.column_window[0]) whole_ = true;
  }
  have_stamp_ = false;
  stamp_ns_ = 0;
  host_ns_ = host_ns;
  packets_ = 0;
  invalid_columns_ = 0;
  dense_count_ = 0;
  std::fill(received_.begin(), received_.end(), std::uint8_t{0});
}

PushResult FrameAssembler::push(std::span<const std::uint8_t> payload,
                                std::int64_t host_receive_ns) noexcept {
  PushResult result;
  LidarPacket packet;
  result.error = LidarPacket::parse(payload, metadata_.format, packet, metadata_.init_id);
  if (result.error != PacketError::none) {
    ++counters_.malformed;
    ++counters_.rejected[static_cast<unsigned>(result.error)];
    if (result.error == PacketError::wrong_size) counters_.last_rejected_size = payload.size();
    return result;
  }
  ++counters_.packets;
  if (open_ && packet.frame_id() != frame_id_) {
    // The last packet of the frame in progress was lost: it ends here.
    result.frame = close();
    if (result.frame) {
      // This packet belongs to the next span, which the caller gives after taking the frame.
      std::memcpy(pending_.data(), payload.data(), payload.size());
      pending_size_ = payload.size();
      pending_host_ns_ = host_receive_ns;
      return result;
    }
  }
  if (!open_) begin(packet, host_receive_ns);
  decode(packet);
  for (unsigned c = 0; c < packet.columns(); ++c) {
    if (packet.column(c).measurement_id == metadata_.column_window[1]) {
      result.frame = close();
      break;
    }
  }
  return result;
}

std::optional<CompletedFrame> FrameAssembler::flush() noexcept { return close(); }

void FrameAssembler::decode(const LidarPacket& packet) noexcept {
  ++packets_;
  switch (metadata_.format.profile) {
    case Profile::legacy: decode_columns<Profile::legacy>(packet); break;
    case Profile::rng19_rfl8_sig16_nir16: decode_columns<Profile::rng19_rfl8_sig16_nir16>(packet); break;
    case Profile::rng19_rfl8_sig16_nir16_dual:
      decode_columns<Profile::rng19_rfl8_sig16_nir16_dual>(packet);
      break;
    case Profile::rng15_rfl8_nir8: decode_columns<Profile::rng15_rfl8_nir8>(packet); break;
    case Profile::fusa_rng15_rfl8_nir8_dual:
      decode_columns<Profile::fusa_rng15_rfl8_nir8_dual>(packet);
      break;
  }
}

template <Profile P>
void FrameAssembler::decode_columns(const LidarPacket& packet) noexcept {
  const bool organized = options_.layout == CloudLayout::organized;
  const std::size_t image = std::size_t{beams_} * columns_;
  const unsigned stride = pixel_bytes(P);
  constexpr bool dual = P == Profile::rng19_rfl8_sig16_nir16_dual || P == Profile::fusa_rng15_rfl8_nir8_dual;
  const bool second = dual && returns_ > 1;
  // First the columns' headers: which to decode, and their times.
  struct Accepted {
    unsigned index;  // in the packet
    unsigned m;      // measurement_id
    std::uint32_t time_offset;
  };
  std::array<Accepted, max_columns_per_packet> accepted;
  unsigned count = 0;
  for (unsigned c = 0; c < packet.columns() && c < max_columns_per_packet; ++c) {
    const Column column = packet.column(c);
    if (!column.valid) {
      ++invalid_columns_;
      ++counters_.invalid_columns;
      continue;
    }
    const unsigned m = column.measurement_id;
    if (received_[m] != 0) {
      ++counters_.duplicate_columns;
      continue;
    }
    received_[m] = 1;
    const auto timestamp = static_cast<std::int64_t>(column.timestamp_ns);
    if (!have_stamp_) {
      stamp_ns_ = timestamp;
      have_stamp_ = true;
    }
    const std::int64_t offset =
        std::clamp<std::int64_t>(timestamp - stamp_ns_, 0, std::numeric_limits<std::uint32_t>::max());
    accepted[count++] = {c, m, static_cast<std::uint32_t>(offset)};
  }
  // Then beam by beam: an organised frame is row-major, so the packet's neighbouring columns of
  // one beam are neighbouring points; writing them together fills whole cache lines at once
  // (rows lie W × 24 bytes apart, a multiple of 4 KiB that maps every row to the same cache set).
  for (unsigned u = 0; u < beams_; ++u) {
    const std::size_t row_start = std::size_t{u} * columns_;
    for (unsigned k = 0; k < count; ++k) {
      const Accepted& col = accepted[k];
      const Pixel px = decode_pixel_as<P>(packet.pixel_bytes(col.index, 0) + std::size_t{u} * stride);
      const std::size_t lut = row_start + col.m;
      float intensity = 0;
      float intensity2 = 0;
      switch (intensity_) {
        case IntensityField::signal: intensity = px.signal; intensity2 = px.signal2; break;
        case IntensityField::reflectivity: intensity = px.reflectivity; intensity2 = px.reflectivity2; break;
        case IntensityField::near_ir:
        case IntensityField::automatic: intensity = intensity2 = px.near_ir; break;
      }
      if (organized) {
        const std::size_t at = organized_index(u, col.m);
        write_point(at, u, col.m, lut, px.range_mm, intensity, col.time_offset, 0);
        if (second) write_point(at + image, u, col.m, lut, px.range2_mm, intensity2, col.time_offset, 1);
      } else {
        if (px.range_mm != 0 && px.range_mm >= min_range_mm_ && px.range_mm <= max_range_mm_) {
          write_point(dense_count_++, u, col.m, lut, px.range_mm, intensity, col.time_offset, 0);
        }
        if (second && px.range2_mm != 0 && px.range2_mm >= min_range_mm_ && px.range2_mm <= max_range_mm_) {
          write_point(dense_count_++, u, col.m, lut, px.range2_mm, intensity2, col.time_offset, 1);
        }
      }
    }
  }
}

void FrameAssembler::write_point(std::size_t index, unsigned row, unsigned column, std::size_t lut,
                                 std::uint32_t range_mm, float intensity, std::uint32_t time_offset,
                                 std::uint8_t return_index) noexcept {
  if (!attached_ || index >= output_.size()) {
    ++counters_.dropped_points;
    return;
  }
  LidarPoint& p = output_[index];
  // Out of the range limits counts as no return: the organised slot stays at the origin.
  if (range_mm != 0 && range_mm >= min_range_mm_ && range_mm <= max_range_mm_) {
    const float r = static_cast<float>(range_mm) - beam_origin_mm_;
    const float* d = &direction_[3 * lut];
    const float* o = &column_origin_[3 * std::size_t{column}];
    p.x = r * d[0] + o[0];
    p.y = r * d[1] + o[1];
    p.z = r * d[2] + o[2];
  } else {
    p.x = p.y = p.z = 0;
  }
  p.intensity = intensity;
  p.time_offset_ns = time_offset;
  p.ring = static_cast<std::uint16_t>(row);
  p.return_index = return_index;
  p.reserved = 0;
}

// Organised frames: columns that never came (lost packets, invalid status) hold no return.
void FrameAssembler::fill_missing_columns() noexcept {
  const std::size_t image = std::size_t{beams_} * columns_;
  for (unsigned m = 0; m < columns_; ++m) {
    if (received_[m] != 0) continue;
    for (unsigned u = 0; u < beams_; ++u) {
      const std::size_t lut = std::size_t{u} * columns_ + m;
      for (unsigned r = 0; r < returns_; ++r) {
        write_point(organized_index(u, m) + r * image, u, m, lut, 0, 0, 0, static_cast<std::uint8_t>(r));
      }
    }
  }
}

std::optional<CompletedFrame> FrameAssembler::close() noexcept {
  if (!open_) return std::nullopt;
  open_ = false;
  const unsigned window = metadata_.window_columns();
  unsigned received = 0;
  for (std::uint8_t r : received_) received += r;
  const unsigned missing = window > received + invalid_columns_ ? window - received - invalid_columns_ : 0;
  const unsigned per_packet = metadata_.format.columns_per_packet;
  if (whole_) counters_.lost_packets += (missing + per_packet - 1) / per_packet;
  if (!whole_ && !options_.emit_partial_frames) {
    ++counters_.partial_frames_dropped;
    return std::nullopt;  // the span stays attached and is refilled
  }
  if (!attached_) {
    ++counters_.frames_without_output;
    return std::nullopt;
  }
  CompletedFrame frame;
  if (options_.layout == CloudLayout::organized) {
    fill_missing_columns();
    frame.point_count = std::min(max_points(), output_.size());
  } else {
    frame.point_count = std::min(dense_count_, output_.size());
  }
  frame.stamp_ns = stamp_ns_;
  frame.host_receive_ns = host_ns_;
  frame.index = frame_index_++;
  frame.frame_id = frame_id_;
  frame.packets = packets_;
  frame.missing_columns = missing;
  frame.invalid_columns = invalid_columns_;
  frame.whole = whole_;
  attached_ = false;  // the span is the caller's until the next set_output
  ++counters_.frames;
  return frame;
}

}  // namespace sim::ouster
