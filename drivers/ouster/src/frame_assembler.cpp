// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/frame_assembler.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <numbers>
#include <type_traits>

namespace sim::ouster {
namespace {

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// Millimetres, at most 2^31 − 1 (far beyond any return: ranges have 20 bits).
std::int32_t to_mm(float metres) {
  const double mm = std::min(static_cast<double>(metres) * 1000.0, double{std::numeric_limits<std::int32_t>::max()});
  return static_cast<std::int32_t>(std::lround(mm));
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
  assembler.build_geometry();
  return assembler;
}

FrameAssembler::FrameAssembler(const Metadata& metadata, AssemblerOptions options)
    : metadata_(metadata), options_(options) {
  beams_ = metadata.beams();
  columns_ = metadata.columns();
  returns_ = options.first_return_only ? 1 : returns_of(metadata.format.profile);
  image_points_ = std::size_t{beams_} * columns_;
  min_range_mm_ = std::max<std::int32_t>(to_mm(options.min_range_m), 1);  // 0 is no return
  max_range_mm_ = options.max_range_m > 0 ? to_mm(options.max_range_m) : std::numeric_limits<std::int32_t>::max();
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
// Angle addition splits d into a beam part and a column part:
//   d = cos φ·cos θa·(cos θe, sin θe, 0) + cos φ·sin θa·(−sin θe, cos θe, 0) + sin φ·(0, 0, 1),
// and lidar_to_sensor (R, t; mm) is linear, so in the sensor frame, metres,
//   d = a_u·E_m + b_u·F_m + g_u,  O_m = (R·o + t) / 1000.
// Everything is computed in double and rounded once to float.
void FrameAssembler::build_geometry() {
  const auto& m = metadata_;
  const auto& s = m.lidar_to_sensor;
  auto rotated = [&s](const std::array<double, 3>& v, unsigned row) {
    return (s[4 * row] * v[0] + s[4 * row + 1] * v[1] + s[4 * row + 2] * v[2]) / 1000.0;
  };
  auto f32 = [](double v) { return static_cast<float>(v); };
  constexpr double pi = std::numbers::pi;
  const double t03 = m.beam_to_lidar[3];
  const double t23 = m.beam_to_lidar[11];
  column_geometry_.resize(columns_);
  for (unsigned col = 0; col < columns_; ++col) {
    const double encoder = 2 * pi * (1.0 - static_cast<double>(col) / columns_);
    const double c = std::cos(encoder);
    const double sn = std::sin(encoder);
    const std::array<double, 3> e{c, sn, 0}, f{-sn, c, 0}, o{t03 * c, t03 * sn, t23};
    column_geometry_[col] = {f32(rotated(e, 0)), f32(rotated(e, 1)), f32(rotated(e, 2)),
                             f32(rotated(f, 0)), f32(rotated(f, 1)), f32(rotated(f, 2)),
                             f32(rotated(o, 0) + s[3] / 1000.0), f32(rotated(o, 1) + s[7] / 1000.0),
                             f32(rotated(o, 2) + s[11] / 1000.0)};
  }
  const std::array<double, 3> up{0, 0, 1};
  beam_geometry_.resize(beams_);
  for (unsigned u = 0; u < beams_; ++u) {
    const double azimuth = -2 * pi * m.beam_azimuth_deg[u] / 360.0;
    const double altitude = 2 * pi * m.beam_altitude_deg[u] / 360.0;
    const double level = std::cos(altitude);
    const double rise = std::sin(altitude);
    beam_geometry_[u] = {f32(level * std::cos(azimuth)), f32(level * std::sin(azimuth)),
                         f32(rise * rotated(up, 0)), f32(rise * rotated(up, 1)), f32(rise * rotated(up, 2))};
  }
  row_shift_.resize(beams_);
  const long w = columns_;
  for (unsigned u = 0; u < beams_; ++u) {
    row_shift_[u] = static_cast<unsigned>((m.pixel_shift_by_row[u] % w + w) % w);
  }
  beam_origin_mm_ = static_cast<float>(m.lidar_origin_to_beam_origin_mm);
}

std::size_t FrameAssembler::max_points() const noexcept {
  return image_points_ * returns_;
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

// The hot path. A packet is decoded beam by beam over its columns: an organised frame is
// row-major, so one beam's pixels in neighbouring columns are neighbouring points, and writing
// them together fills whole cache lines at once (rows lie W × 24 bytes apart, a multiple of 4 KiB
// that maps every row to the same cache set). Each beam goes through three short loops over the
// packet's columns: gather the pixels (load_beam), compute the points in small arrays
// (locate_beam: branch-free arithmetic the compiler vectorises) and write them out as whole
// 24-byte points (store_organized, store_dense). Everything that does not change within a packet
// (which columns count, their times and geometry, the range limits, the intensity channel, the
// room in the output span) is decided once per packet or per beam, never per point.

// The columns of one packet that this frame takes, as arrays over the column (so the per-beam
// loops over them vectorise).
struct FrameAssembler::PacketColumns {
  static constexpr unsigned capacity = max_columns_per_packet;
  unsigned count = 0;
  std::size_t pixel_bytes = 0;
  const std::uint8_t* first_pixel[capacity];
  std::uint32_t measurement_id[capacity];
  std::uint32_t time_offset[capacity];
  alignas(16) float ex[capacity];
  alignas(16) float ey[capacity];
  alignas(16) float ez[capacity];
  alignas(16) float fx[capacity];
  alignas(16) float fy[capacity];
  alignas(16) float fz[capacity];
  alignas(16) float ox[capacity];
  alignas(16) float oy[capacity];
  alignas(16) float oz[capacity];
};

// One beam's pixels across a packet's columns: raw range and intensity, then each return's
// x, y, z and intensity as arrays (what the loop vectoriser handles best).
struct FrameAssembler::BeamPixels {
  static constexpr unsigned capacity = max_columns_per_packet;
  alignas(16) std::int32_t range[capacity];
  alignas(16) std::int32_t range2[capacity];
  alignas(16) std::int32_t intensity[capacity];
  alignas(16) std::int32_t intensity2[capacity];
  alignas(16) float x[capacity], y[capacity], z[capacity], value[capacity];
  alignas(16) float x2[capacity], y2[capacity], z2[capacity], value2[capacity];
};

namespace {

// The pixel's channel that goes into LidarPoint::intensity, for the first or second return.
template <bool Second>
std::int32_t channel(const Pixel& p, IntensityField field) noexcept {
  switch (field) {
    case IntensityField::signal: return Second ? p.signal2 : p.signal;
    case IntensityField::reflectivity: return Second ? p.reflectivity2 : p.reflectivity;
    case IntensityField::near_ir:
    case IntensityField::automatic: break;  // resolved at construction
  }
  return p.near_ir;
}

// One whole point.
inline void store_point(LidarPoint& p, float x, float y, float z, float intensity, std::uint32_t time_offset,
                        std::uint16_t ring, std::uint8_t return_index) noexcept {
  p.x = x;
  p.y = y;
  p.z = z;
  p.intensity = intensity;
  p.time_offset_ns = time_offset;
  p.ring = ring;
  p.return_index = return_index;
  p.reserved = 0;
}

}  // namespace

template <Profile P>
void FrameAssembler::decode_columns(const LidarPacket& packet) noexcept {
  PacketColumns columns;
  accept_columns(packet, columns);
  if (columns.count == 0) return;
  constexpr bool dual = P == Profile::rng19_rfl8_sig16_nir16_dual || P == Profile::fusa_rng15_rfl8_nir8_dual;
  if (dual && returns_ > 1) {
    decode_beams<P, true>(columns);
  } else {
    decode_beams<P, false>(columns);
  }
}

// Which of the packet's columns count (valid, not seen before in this frame), with their time
// after the frame's stamp and their geometry.
void FrameAssembler::accept_columns(const LidarPacket& packet, PacketColumns& out) noexcept {
  out.count = 0;
  out.pixel_bytes = pixel_bytes(metadata_.format.profile);
  for (unsigned c = 0; c < packet.columns() && c < PacketColumns::capacity; ++c) {
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
    const unsigned k = out.count++;
    const ColumnGeometry& g = column_geometry_[m];
    out.first_pixel[k] = packet.pixel_bytes(c, 0);
    out.measurement_id[k] = m;
    out.time_offset[k] = static_cast<std::uint32_t>(offset);
    out.ex[k] = g.ex;
    out.ey[k] = g.ey;
    out.ez[k] = g.ez;
    out.fx[k] = g.fx;
    out.fy[k] = g.fy;
    out.fz[k] = g.fz;
    out.ox[k] = g.ox;
    out.oy[k] = g.oy;
    out.oz[k] = g.oz;
  }
}

template <Profile P, bool Dual>
void FrameAssembler::decode_beams(const PacketColumns& columns) noexcept {
  BeamPixels px;
  if (options_.layout == CloudLayout::dense) {
    for (unsigned u = 0; u < beams_; ++u) {
      load_beam<P, Dual>(columns, u, px);
      locate_beam<Dual>(columns, u, px);
      store_dense<Dual>(columns, u, px);
    }
    return;
  }
  // A span with room for the whole frame (always, from a SIM loan) needs no check per point.
  if (attached_ && output_.size() >= max_points()) {
    for (unsigned u = 0; u < beams_; ++u) {
      load_beam<P, Dual>(columns, u, px);
      locate_beam<Dual>(columns, u, px);
      store_organized<Dual, false>(columns, u, px);
    }
  } else {
    for (unsigned u = 0; u < beams_; ++u) {
      load_beam<P, Dual>(columns, u, px);
      locate_beam<Dual>(columns, u, px);
      store_organized<Dual, true>(columns, u, px);
    }
  }
}

template <Profile P, bool Dual>
void FrameAssembler::load_beam(const PacketColumns& columns, unsigned beam, BeamPixels& out) const noexcept {
  const std::size_t offset = std::size_t{beam} * columns.pixel_bytes;
  const IntensityField field = intensity_;
  const unsigned count = columns.count;
  // The pixels a few beams further down each column, so they are in L1 when their beam comes
  // (16 columns 0.4–2 kB apart are more streams than the hardware prefetcher follows).
  constexpr unsigned ahead_bytes = 256;
  if (offset + ahead_bytes < std::size_t{beams_} * columns.pixel_bytes) {
    for (unsigned k = 0; k < count; ++k) __builtin_prefetch(columns.first_pixel[k] + offset + ahead_bytes);
  }
  // One loop per intensity channel, so the choice is not made again for every pixel.
  auto gather = [&](auto channel_constant) {
    constexpr IntensityField f = decltype(channel_constant)::value;
    for (unsigned k = 0; k < count; ++k) {
      const Pixel p = decode_pixel_as<P>(columns.first_pixel[k] + offset);
      out.range[k] = static_cast<std::int32_t>(p.range_mm);
      out.intensity[k] = channel<false>(p, f);
      if constexpr (Dual) {
        out.range2[k] = static_cast<std::int32_t>(p.range2_mm);
        out.intensity2[k] = channel<true>(p, f);
      }
    }
  };
  using F = IntensityField;
  switch (field) {
    case F::signal: gather(std::integral_constant<F, F::signal>{}); break;
    case F::reflectivity: gather(std::integral_constant<F, F::reflectivity>{}); break;
    case F::near_ir:
    case F::automatic: gather(std::integral_constant<F, F::near_ir>{}); break;  // automatic is resolved at construction
  }
}

// x, y, z of each return: (r − n)·d + O, or the origin when the range is outside [lo, hi] (0, no
// return, always is). Branch-free arithmetic on arrays: the compiler vectorises the loops.
template <bool Dual>
void FrameAssembler::locate_beam(const PacketColumns& columns, unsigned beam, BeamPixels& px) const noexcept {
  const BeamGeometry g = beam_geometry_[beam];
  const std::int32_t lo = min_range_mm_;
  const std::int32_t hi = max_range_mm_;
  const float n = beam_origin_mm_;
  const unsigned count = columns.count;
  auto place = [&](const std::int32_t* range, const std::int32_t* intensity, float* x, float* y, float* z,
                   float* value) {
    for (unsigned k = 0; k < count; ++k) {
      const float dx = g.a * columns.ex[k] + g.b * columns.fx[k] + g.gx;
      const float dy = g.a * columns.ey[k] + g.b * columns.fy[k] + g.gy;
      const float dz = g.a * columns.ez[k] + g.b * columns.fz[k] + g.gz;
      // All ones for a return inside the limits, else 0 (+0.0 once applied to a float's bits).
      const std::uint32_t keep = 0u - static_cast<std::uint32_t>((range[k] >= lo) & (range[k] <= hi));
      const float r = static_cast<float>(range[k]) - n;
      x[k] = std::bit_cast<float>(std::bit_cast<std::uint32_t>(r * dx + columns.ox[k]) & keep);
      y[k] = std::bit_cast<float>(std::bit_cast<std::uint32_t>(r * dy + columns.oy[k]) & keep);
      z[k] = std::bit_cast<float>(std::bit_cast<std::uint32_t>(r * dz + columns.oz[k]) & keep);
      value[k] = static_cast<float>(intensity[k]);
    }
  };
  place(px.range, px.intensity, px.x, px.y, px.z, px.value);
  if constexpr (Dual) place(px.range2, px.intensity2, px.x2, px.y2, px.z2, px.value2);
}

// Organised: pixel (u, m) goes to row u, destaggered column (m + shift_u) mod W; the second
// return's image follows the first's. Checked: the span may be missing or short; points beyond
// it are counted as dropped.
template <bool Dual, bool Checked>
void FrameAssembler::store_organized(const PacketColumns& columns, unsigned beam, const BeamPixels& px) noexcept {
  LidarPoint* out = output_.data();
  const std::size_t limit = attached_ ? output_.size() : 0;
  const std::size_t row = std::size_t{beam} * columns_;
  const std::size_t image = image_points_;
  const unsigned shift = row_shift_[beam];
  const unsigned w = columns_;
  const auto ring = static_cast<std::uint16_t>(beam);
  const unsigned count = columns.count;
  if constexpr (!Checked) {
    // The sensor sends columns in order: the next packet's columns of this row follow these.
    // Ask for their cache lines now; when that packet comes (127 rows of work later) the stores
    // find them in cache instead of each waiting for its line from memory. A point every 48
    // bytes touches every 64-byte line; the index wraps within the row like the columns do.
    unsigned next = columns.measurement_id[count - 1] + 1 + shift;  // < 2W
    next = next >= w ? next - w : next;
    for (unsigned j = 0; j < count; j += 2) {
      const unsigned c = next + j;  // no % (a division): next < W and j < W
      const std::size_t at = row + (c >= w ? c - w : c);
      __builtin_prefetch(&out[at], 1);
      if constexpr (Dual) __builtin_prefetch(&out[at + image], 1);
    }
  }
  std::uint64_t dropped = 0;
  for (unsigned k = 0; k < count; ++k) {
    unsigned c = columns.measurement_id[k] + shift;
    c = c >= w ? c - w : c;
    const std::size_t at = row + c;
    if (!Checked || at < limit) {
      store_point(out[at], px.x[k], px.y[k], px.z[k], px.value[k], columns.time_offset[k], ring, 0);
    } else {
      ++dropped;
    }
    if constexpr (Dual) {
      if (!Checked || at + image < limit) {
        store_point(out[at + image], px.x2[k], px.y2[k], px.z2[k], px.value2[k], columns.time_offset[k], ring, 1);
      } else {
        ++dropped;
      }
    }
  }
  counters_.dropped_points += dropped;
}

// Dense: only returns inside the range limits, in packet order (beam by beam, column by column,
// first then second return).
template <bool Dual>
void FrameAssembler::store_dense(const PacketColumns& columns, unsigned beam, const BeamPixels& px) noexcept {
  LidarPoint* out = output_.data();
  const std::size_t limit = attached_ ? output_.size() : 0;
  const std::int32_t lo = min_range_mm_;
  const std::int32_t hi = max_range_mm_;
  const auto ring = static_cast<std::uint16_t>(beam);
  const unsigned count = columns.count;
  std::size_t next = dense_count_;
  std::uint64_t dropped = 0;
  // Every pixel is written at the next free place, which advances only for a return: no
  // branch on the data (a scene is half returns, a branch on them mispredicts half the time).
  auto keep = [&](std::int32_t range, float x, float y, float z, float value, std::uint32_t time_offset,
                  std::uint8_t return_index) {
    const bool hit = (range >= lo) & (range <= hi);
    if (next < limit) {
      store_point(out[next], x, y, z, value, time_offset, ring, return_index);
    } else {
      dropped += hit;
    }
    next += hit;
  };
  for (unsigned k = 0; k < count; ++k) {
    keep(px.range[k], px.x[k], px.y[k], px.z[k], px.value[k], columns.time_offset[k], 0);
    if constexpr (Dual) keep(px.range2[k], px.x2[k], px.y2[k], px.z2[k], px.value2[k], columns.time_offset[k], 1);
  }
  dense_count_ = next;
  counters_.dropped_points += dropped;
}

// Organised frames: columns that never came (lost packets, invalid status) hold no return.
void FrameAssembler::fill_missing_columns() noexcept {
  const std::size_t limit = attached_ ? output_.size() : 0;
  for (unsigned m = 0; m < columns_; ++m) {
    if (received_[m] != 0) continue;
    for (unsigned u = 0; u < beams_; ++u) {
      for (unsigned r = 0; r < returns_; ++r) {
        const std::size_t at = organized_index(u, m) + r * image_points_;
        if (at < limit) {
          store_point(output_[at], 0, 0, 0, 0, 0, static_cast<std::uint16_t>(u), static_cast<std::uint8_t>(r));
        } else {
          ++counters_.dropped_points;
        }
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
