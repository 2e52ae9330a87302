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
  // Mid-frame, the points decoded so far went elsewhere: what follows is a partial frame (not
  // late packets of a frame already closed).
  if (open_) {
    open_ = false;
    have_frame_id_ = false;
  }
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
  have_frame_id_ = false;
  pending_size_ = 0;
}

// A frame_id's columns come in measurement id order from 0 up, so a window that wraps through
// column 0 (as [370, 85]) arrives as its end (0 … 85) and then its start (370 … W − 1): in
// arrival order it begins at column 0 and ends at column W − 1.
unsigned FrameAssembler::first_column() const noexcept {
  const auto& window = metadata_.column_window;
  return window[0] > window[1] ? 0 : window[0];
}

unsigned FrameAssembler::last_column() const noexcept {
  const auto& window = metadata_.column_window;
  return window[0] > window[1] ? columns_ - 1 : window[1];
}

// A packet of the frame already closed, or of an earlier frame, arrived late (reordered on the
// way): ouster-sdk drops it (FrameBatcher, frame_id_difference <= 0), and so does SIM, instead of
// closing the frame in progress on it. Further back than a few frames is a sensor that restarted
// its frame counter: a new frame.
bool FrameAssembler::late(std::uint32_t frame_id) const noexcept {
  if (!have_frame_id_) return false;
  constexpr std::uint32_t late_frames = 4;
  const std::uint32_t mask = metadata_.format.fusa_header ? 0xffffffffU : 0xffffU;
  const std::uint32_t behind = (frame_id_ - frame_id) & mask;
  if (behind == 0) return !open_;
  return behind <= late_frames;
}

void FrameAssembler::begin(const LidarPacket& packet, std::int64_t host_ns) noexcept {
  open_ = true;
  frame_id_ = packet.frame_id();
  have_frame_id_ = true;
  whole_ = false;
  for (unsigned c = 0; c < packet.columns(); ++c) {
    if (packet.column(c).measurement_id == first_column()) whole_ = true;
  }
  have_stamp_ = false;
  stamp_ns_ = 0;
  host_ns_ = host_ns;
  packets_ = 0;
  invalid_columns_ = 0;
  dropped_points_ = 0;
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
  for (unsigned c = 0; c < packet.columns(); ++c) {
    const Column& column = packet.column(c);
    if (!column.valid || column.timestamp_ns > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) continue;
    result.packet_ns = static_cast<std::int64_t>(column.timestamp_ns);  // a late packet's too
    break;
  }
  if (late(packet.frame_id())) {
    ++counters_.late_packets;
    return result;
  }
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
  const unsigned last = last_column();
  for (unsigned c = 0; c < packet.columns(); ++c) {
    if (packet.column(c).measurement_id == last) {
      result.frame = close();
      break;
    }
  }
  return result;
}

std::optional<CompletedFrame> FrameAssembler::finish() noexcept { return close(); }

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
// them together fills whole cache lines at once. Four columns at a time go through registers
// only: gather their pixels, locate the points with four-lane vector arithmetic (GCC and Clang
// vector extensions: SSE on x86-64, NEON on ARM, one source), and write each point as one
// 16-byte (x, y, z, intensity) and one 8-byte (time, ring, return) store. Everything that does
// not change within a packet (which columns count, their times and geometry, the range limits,
// the intensity channel, the room in the output span) is decided once per packet or per beam,
// never per point.

namespace {

constexpr unsigned lanes = 4;
using Floats = float __attribute__((vector_size(4 * lanes)));
using Ints = std::int32_t __attribute__((vector_size(4 * lanes)));

Floats load_floats(const float* from) noexcept {
  Floats v;
  std::memcpy(&v, from, sizeof v);
  return v;
}

}  // namespace

// The columns of one packet that this frame takes, as arrays over the column, padded to whole
// groups of lanes: a padding lane reads the first column's pixels and is never stored.
struct detail::PacketColumns {
  static constexpr unsigned capacity = FrameAssembler::max_columns_per_packet;
  static_assert(capacity % lanes == 0, "padding must stay inside the arrays");
  unsigned count = 0;  // accepted columns, without the padding
  bool consecutive = true;  // measurement_id[k] == measurement_id[0] + k (no column lost or invalid)
  std::size_t pixel_bytes = 0;
  std::size_t beam_bytes = 0;  // a column's pixels: beams × pixel_bytes
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

  void put(unsigned k, const std::uint8_t* pixels, std::uint32_t m, std::uint32_t time,
           const ColumnGeometry& g) noexcept {
    first_pixel[k] = pixels;
    measurement_id[k] = m;
    time_offset[k] = time;
    ex[k] = g.ex;
    ey[k] = g.ey;
    ez[k] = g.ez;
    fx[k] = g.fx;
    fy[k] = g.fy;
    fz[k] = g.fz;
    ox[k] = g.ox;
    oy[k] = g.oy;
    oz[k] = g.oz;
  }
};

namespace {

using detail::PacketColumns;

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

// One beam's raw ranges (mm) and intensities in four neighbouring columns, both returns.
struct FourPixels {
  Ints range, intensity, range2, intensity2;
};

// Four vectors transposed: lane j of result i is lane i of input j (eight shuffles).
template <typename V>
[[gnu::always_inline]] inline std::array<V, lanes> transpose(V a, V b, V c, V d) noexcept {
#if defined(__has_builtin)
#if __has_builtin(__builtin_shufflevector)
#define SIM_OUSTER_SHUFFLE 1
#endif
#endif
#ifdef SIM_OUSTER_SHUFFLE
  const V ab_low = __builtin_shufflevector(a, b, 0, 4, 1, 5);  // a0 b0 a1 b1
  const V cd_low = __builtin_shufflevector(c, d, 0, 4, 1, 5);
  const V ab_high = __builtin_shufflevector(a, b, 2, 6, 3, 7);  // a2 b2 a3 b3
  const V cd_high = __builtin_shufflevector(c, d, 2, 6, 3, 7);
  return {__builtin_shufflevector(ab_low, cd_low, 0, 1, 4, 5), __builtin_shufflevector(ab_low, cd_low, 2, 3, 6, 7),
          __builtin_shufflevector(ab_high, cd_high, 0, 1, 4, 5), __builtin_shufflevector(ab_high, cd_high, 2, 3, 6, 7)};
#else  // GCC before 12: the compiler finds its own shuffles
  std::array<V, lanes> out;
  for (unsigned j = 0; j < lanes; ++j) out[j] = V{a[j], b[j], c[j], d[j]};
  return out;
#endif
}

// Profiles whose pixel is three or four little-endian 32-bit words (LEGACY, RNG19 single and
// dual): the four pixels are loaded whole and transposed, so each word of the four columns is one
// vector and every field is a mask or a shift of it, instead of being assembled lane by lane.
// A 12-byte pixel is always followed by at least 4 bytes of the same packet (the next pixel, a
// column header or status block, or the footer); they are read and not used.
template <Profile P>
constexpr bool whole_word_pixels = std::endian::native == std::endian::little &&
                                   (P == Profile::legacy || P == Profile::rng19_rfl8_sig16_nir16 ||
                                    P == Profile::rng19_rfl8_sig16_nir16_dual);

[[gnu::always_inline]] inline std::array<Ints, lanes> pixel_words(const PacketColumns& columns, unsigned k,
                                                                  std::size_t offset) noexcept {
  std::array<Ints, lanes> pixel;
  for (unsigned j = 0; j < lanes; ++j) std::memcpy(&pixel[j], columns.first_pixel[k + j] + offset, sizeof(Ints));
  return transpose(pixel[0], pixel[1], pixel[2], pixel[3]);
}

// The fields of decode_pixel_as() for these profiles, from the words: (w >> s) & m.
template <Profile P, IntensityField F>
[[gnu::always_inline]] inline FourPixels fields_of_words(const std::array<Ints, lanes>& w) noexcept {
  auto bits = [](Ints word, int shift, std::int32_t mask) { return (word >> shift) & mask; };
  FourPixels out{};
  if constexpr (P == Profile::rng19_rfl8_sig16_nir16_dual) {
    // w0: range 19 | flags 5 | reflectivity 8; w1: the same for the second return;
    // w2: signal 16 | signal2 16; w3: near-IR 16 | reserved 16.
    out.range = bits(w[0], 0, 0x7ffff);
    out.range2 = bits(w[1], 0, 0x7ffff);
    if constexpr (F == IntensityField::signal) {
      out.intensity = bits(w[2], 0, 0xffff);
      out.intensity2 = bits(w[2], 16, 0xffff);
    } else if constexpr (F == IntensityField::reflectivity) {
      out.intensity = bits(w[0], 24, 0xff);
      out.intensity2 = bits(w[1], 24, 0xff);
    } else {
      out.intensity = out.intensity2 = bits(w[3], 0, 0xffff);
    }
  } else {
    // w0: range (LEGACY 20 bits, RNG19 19 bits and flags); w1: reflectivity 8 | 8 | signal 16;
    // w2: near-IR 16 | 16.
    out.range = bits(w[0], 0, P == Profile::legacy ? 0xfffff : 0x7ffff);
    if constexpr (F == IntensityField::signal) {
      out.intensity = bits(w[1], 16, 0xffff);
    } else if constexpr (F == IntensityField::reflectivity) {
      out.intensity = bits(w[1], 0, 0xff);
    } else {
      out.intensity = bits(w[2], 0, 0xffff);
    }
  }
  return out;
}

template <Profile P, bool Dual, IntensityField F>
[[gnu::always_inline]] inline FourPixels gather_four(const PacketColumns& columns, unsigned k, std::size_t offset) noexcept {
  if constexpr (whole_word_pixels<P>) {
    return fields_of_words<P, F>(pixel_words(columns, k, offset));
  } else {
    FourPixels out{};
    for (unsigned j = 0; j < lanes; ++j) {
      const Pixel p = decode_pixel_as<P>(columns.first_pixel[k + j] + offset);
      out.range[j] = static_cast<std::int32_t>(p.range_mm);
      out.intensity[j] = channel<false>(p, F);
      if constexpr (Dual) {
        out.range2[j] = static_cast<std::int32_t>(p.range2_mm);
        out.intensity2[j] = channel<true>(p, F);
      }
    }
    return out;
  }
}

// The direction d = a·E + b·F + g of one beam in four neighbouring columns, metres per
// millimetre of range (see build_geometry()); both returns share it.
struct FourDirections {
  Floats x, y, z;
};

[[gnu::always_inline]] inline FourDirections directions(const PacketColumns& c, unsigned k, const detail::BeamGeometry& g) noexcept {
  return {g.a * load_floats(c.ex + k) + g.b * load_floats(c.fx + k) + g.gx,
          g.a * load_floats(c.ey + k) + g.b * load_floats(c.fy + k) + g.gy,
          g.a * load_floats(c.ez + k) + g.b * load_floats(c.fz + k) + g.gz};
}

// The range limits and the beam origin offset n, as the arithmetic needs them.
struct RangeTerms {
  std::int32_t lo, hi;
  float n;
};

// One return of one beam in four neighbouring columns, located: (r − n)·d + O, or the origin
// (+0.0) where the range is outside [lo, hi] (0, no return, always is). No branch.
struct FourPoints {
  Floats x, y, z, value;
  Ints keep;  // all ones for a point, else 0
};

[[gnu::always_inline]] inline FourPoints locate(const FourDirections& d, const PacketColumns& c, unsigned k, Ints range, Ints intensity,
                  const RangeTerms& t) noexcept {
  const Ints keep = (range >= t.lo) & (range <= t.hi);
  const Floats r = __builtin_convertvector(range, Floats) - t.n;
  auto masked = [&keep](Floats v) { return std::bit_cast<Floats>(std::bit_cast<Ints>(v) & keep); };
  return {masked(r * d.x + load_floats(c.ox + k)), masked(r * d.y + load_floats(c.oy + k)),
          masked(r * d.z + load_floats(c.oz + k)), __builtin_convertvector(intensity, Floats), keep};
}

// A point's last 8 bytes (time, ring, return) as one integer, so that each point is two stores:
// the bytes of the time or-ed with those of the ring and return, which are made once per beam.
struct PointTail {
  std::uint32_t time_offset_ns;
  std::uint16_t ring;
  std::uint8_t return_index;
  std::uint8_t reserved;
};
static_assert(sizeof(PointTail) == 8 && offsetof(LidarPoint, time_offset_ns) == 16 && sizeof(LidarPoint) == 24,
              "a point is 16 bytes of floats and this tail");

[[gnu::always_inline]] inline std::uint64_t tail_bits(const PointTail& tail) noexcept {
  std::uint64_t bits;
  std::memcpy(&bits, &tail, sizeof bits);
  return bits;
}

// The four points of one return as one (x, y, z, intensity) vector each.
[[gnu::always_inline]] inline std::array<Floats, lanes> point_vectors(const FourPoints& p) noexcept {
  return transpose(p.x, p.y, p.z, p.value);
}

[[gnu::always_inline]] inline void store_point(LidarPoint& to, Floats xyzi, std::uint64_t tail) noexcept {
  std::memcpy(static_cast<void*>(&to), &xyzi, sizeof xyzi);
  std::memcpy(reinterpret_cast<unsigned char*>(&to) + sizeof xyzi, &tail, sizeof tail);
}

// Where one beam's points go: copies of the assembler's state in locals, which the stores into
// the output cannot alias (so nothing is reloaded after each point).
struct BeamOutput {
  LidarPoint* points;
  std::size_t limit;   // points the span holds
  std::size_t row;     // organised: the beam's first point in the first return's image
  std::size_t image;   // organised: points in one return's image (H × W)
  unsigned shift;      // organised: destaggering, column m goes to (m + shift) mod width
  unsigned width;
  std::uint64_t ring_bits[2];  // tail_bits of the ring and return 0, 1
  std::size_t next;    // dense: the next free place
  std::uint64_t dropped = 0;
  LidarPoint* run = nullptr;   // organised run: where the packet's first column goes in this row
};

// Organised: pixel (u, m) goes to row u, destaggered column (m + shift) mod W; the second
// return's image follows the first's. Checked: the span may be missing or short; points beyond
// it are counted as dropped.
template <bool Dual, bool Checked>
[[gnu::always_inline]] inline void store_organized(BeamOutput& o, const PacketColumns& c, unsigned k, unsigned n,
                                                   const FourPoints& first, const FourPoints& second) noexcept {
  const std::array<Floats, lanes> a = point_vectors(first);
  std::array<Floats, lanes> b{};
  if constexpr (Dual) b = point_vectors(second);
  auto put = [&o](std::size_t at, Floats xyzi, std::uint64_t tail) {
    if (!Checked || at < o.limit) {
      store_point(o.points[at], xyzi, tail);
    } else {
      ++o.dropped;
    }
  };
  for (unsigned j = 0; j < n; ++j) {
    unsigned column = c.measurement_id[k + j] + o.shift;
    column = column >= o.width ? column - o.width : column;  // no % (a division): both < W
    const std::size_t at = o.row + column;
    const std::uint64_t time = tail_bits({c.time_offset[k + j], 0, 0, 0});
    put(at, a[j], time | o.ring_bits[0]);
    if constexpr (Dual) put(at + o.image, b[j], time | o.ring_bits[1]);
  }
}

// Organised, the usual case: the packet's columns are consecutive and this row's part of them
// does not wrap around the row's end, so column k goes to run[k]: no index arithmetic per point.
template <bool Dual>
[[gnu::always_inline]] inline void store_run(const BeamOutput& o, const PacketColumns& c, unsigned k, unsigned n,
                                             const FourPoints& first, const FourPoints& second) noexcept {
  const std::array<Floats, lanes> a = point_vectors(first);
  std::array<Floats, lanes> b{};
  if constexpr (Dual) b = point_vectors(second);
  LidarPoint* to = o.run + k;
  for (unsigned j = 0; j < n; ++j) {
    const std::uint64_t time = tail_bits({c.time_offset[k + j], 0, 0, 0});
    store_point(to[j], a[j], time | o.ring_bits[0]);
    if constexpr (Dual) store_point(to[j + o.image], b[j], time | o.ring_bits[1]);
  }
}

// Dense: only returns inside the range limits, in packet order (column by column, first then
// second return). Every pixel is written at the next free place, which advances only for a
// point: no branch on the data (a scene is half returns, a branch on them mispredicts half the
// time).
template <bool Dual>
[[gnu::always_inline]] inline void store_dense(BeamOutput& o, const PacketColumns& c, unsigned k, unsigned n,
                                               const FourPoints& first, const FourPoints& second) noexcept {
  const std::array<Floats, lanes> a = point_vectors(first);
  std::array<Floats, lanes> b{};
  if constexpr (Dual) b = point_vectors(second);
  auto put = [&o](bool hit, Floats xyzi, std::uint64_t tail) {
    if (o.next < o.limit) {
      store_point(o.points[o.next], xyzi, tail);
    } else {
      o.dropped += hit;
    }
    o.next += hit;
  };
  for (unsigned j = 0; j < n; ++j) {
    const std::uint64_t time = tail_bits({c.time_offset[k + j], 0, 0, 0});
    put(first.keep[j] != 0, a[j], time | o.ring_bits[0]);
    if constexpr (Dual) put(second.keep[j] != 0, b[j], time | o.ring_bits[1]);
  }
}

// The sensor sends columns in order: the next packet's columns of this row follow these. Ask
// for their cache lines now; when that packet comes (a whole packet's rows of work later) the
// stores find them in cache instead of each waiting for its line from memory. A point every 48
// bytes touches every 64-byte line; the index wraps within the row like the columns do.
void prefetch_next_columns(const BeamOutput& o, const PacketColumns& c, unsigned returns) noexcept {
  unsigned next = c.measurement_id[c.count - 1] + 1 + o.shift;  // < 2W
  next = next >= o.width ? next - o.width : next;
  for (unsigned j = 0; j < c.count; j += 2) {
    const unsigned column = next + j;  // no % (a division): next < W and j < W
    const std::size_t at = o.row + (column >= o.width ? column - o.width : column);
    for (unsigned r = 0; r < returns; ++r) __builtin_prefetch(&o.points[at + r * o.image], 1);
  }
}

enum class Store { organized_run, organized, organized_checked, dense };

// One beam of a packet: four columns at a time, gathered, located and stored.
template <Profile P, bool Dual, IntensityField F, Store S>
void decode_beam(const PacketColumns& columns, const detail::BeamGeometry& g, const RangeTerms& terms,
                 unsigned beam, BeamOutput& out) noexcept {
  const std::size_t offset = std::size_t{beam} * columns.pixel_bytes;
  if constexpr (S == Store::organized || S == Store::organized_run) prefetch_next_columns(out, columns, Dual ? 2 : 1);
  // The pixels a few beams further down each column, so they are in L1 when their beam comes
  // (16 columns 0.4–2 kB apart are more streams than the hardware prefetcher follows).
  constexpr unsigned ahead_bytes = 256;
  if (offset + ahead_bytes < columns.beam_bytes) {
    for (unsigned k = 0; k < columns.count; ++k) __builtin_prefetch(columns.first_pixel[k] + offset + ahead_bytes);
  }
  for (unsigned k = 0; k < columns.count; k += lanes) {
    const FourPixels px = gather_four<P, Dual, F>(columns, k, offset);
    const FourDirections d = directions(columns, k, g);
    const FourPoints first = locate(d, columns, k, px.range, px.intensity, terms);
    const FourPoints second = Dual ? locate(d, columns, k, px.range2, px.intensity2, terms) : first;
    auto store = [&](unsigned n) {
      if constexpr (S == Store::dense) {
        store_dense<Dual>(out, columns, k, n, first, second);
      } else if constexpr (S == Store::organized_run) {
        store_run<Dual>(out, columns, k, n, first, second);
      } else {
        store_organized<Dual, S == Store::organized_checked>(out, columns, k, n, first, second);
      }
    };
    const unsigned n = std::min(lanes, columns.count - k);
    if (n == lanes) {
      store(lanes);  // a whole group: the lane loop unrolls
    } else {
      store(n);
    }
  }
}

// One whole point from scalars (columns that never came).
inline void store_scalars(LidarPoint& p, float x, float y, float z, float intensity, std::uint32_t time_offset,
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
    decode_beams<P, dual>(columns);
  } else {
    decode_beams<P, false>(columns);
  }
}

// Which of the packet's columns count (valid, not seen before in this frame), with their time
// after the frame's stamp and their geometry.
void FrameAssembler::accept_columns(const LidarPacket& packet, PacketColumns& out) noexcept {
  out.count = 0;
  out.consecutive = true;
  out.pixel_bytes = pixel_bytes(metadata_.format.profile);
  out.beam_bytes = out.pixel_bytes * beams_;
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
    out.consecutive = out.consecutive && (out.count == 0 || m == out.measurement_id[0] + out.count);
    if (!have_stamp_) {
      stamp_ns_ = static_cast<std::int64_t>(column.timestamp_ns);
      have_stamp_ = true;
    }
    // In the sensor's unsigned clock: any two stamps of a corrupt packet subtract without overflow.
    const auto first = static_cast<std::uint64_t>(stamp_ns_);
    const std::uint64_t after = column.timestamp_ns >= first ? column.timestamp_ns - first : 0;
    const auto offset =
        static_cast<std::uint32_t>(std::min<std::uint64_t>(after, std::numeric_limits<std::uint32_t>::max()));
    out.put(out.count++, packet.pixel_bytes(c, 0), m, offset, column_geometry_[m]);
  }
  for (unsigned k = out.count; k % lanes != 0; ++k) out.put(k, out.first_pixel[0], 0, 0, {});
}

namespace {

// Store::organized_run where it applies to this row (out.run set), else `store`.
Store row_store(Store store, const PacketColumns& columns, BeamOutput& out) noexcept {
  if (store != Store::organized || !columns.consecutive) return store;
  unsigned start = columns.measurement_id[0] + out.shift;  // < 2W
  start = start >= out.width ? start - out.width : start;
  if (start + columns.count > out.width) return store;  // wraps around the row's end
  out.run = out.points + out.row + start;
  return Store::organized_run;
}

}  // namespace

// One instance of the beam loop per intensity channel and per kind of store, so no pixel asks
// which one it wants.
template <Profile P, bool Dual>
void FrameAssembler::decode_beams(const PacketColumns& columns) noexcept {
  using F = IntensityField;
  switch (intensity_) {
    case F::signal: decode_beams_as<P, Dual, F::signal>(columns); break;
    case F::reflectivity: decode_beams_as<P, Dual, F::reflectivity>(columns); break;
    case F::near_ir:
    case F::automatic: decode_beams_as<P, Dual, F::near_ir>(columns); break;  // automatic is resolved at construction
  }
}

template <Profile P, bool Dual, IntensityField F>
void FrameAssembler::decode_beams_as(const PacketColumns& columns) noexcept {
  const RangeTerms terms{min_range_mm_, max_range_mm_, beam_origin_mm_};
  BeamOutput out{output_.data(), attached_ ? output_.size() : 0, 0, image_points_, 0, columns_, {}, dense_count_};
  // A span with room for the whole frame (always, from a SIM loan) needs no check per point.
  const Store store = options_.layout == CloudLayout::dense   ? Store::dense
                      : out.limit >= max_points()             ? Store::organized
                                                              : Store::organized_checked;
  for (unsigned u = 0; u < beams_; ++u) {
    out.row = std::size_t{u} * columns_;
    out.shift = row_shift_[u];
    const auto ring = static_cast<std::uint16_t>(u);
    out.ring_bits[0] = tail_bits({0, ring, 0, 0});
    out.ring_bits[1] = tail_bits({0, ring, 1, 0});
    const detail::BeamGeometry& g = beam_geometry_[u];
    switch (row_store(store, columns, out)) {
      case Store::organized_run: decode_beam<P, Dual, F, Store::organized_run>(columns, g, terms, u, out); break;
      case Store::organized: decode_beam<P, Dual, F, Store::organized>(columns, g, terms, u, out); break;
      case Store::organized_checked: decode_beam<P, Dual, F, Store::organized_checked>(columns, g, terms, u, out); break;
      case Store::dense: decode_beam<P, Dual, F, Store::dense>(columns, g, terms, u, out); break;
    }
  }
  dense_count_ = out.next;
  counters_.dropped_points += out.dropped;
  dropped_points_ += out.dropped;
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
          store_scalars(output_[at], 0, 0, 0, 0, 0, static_cast<std::uint16_t>(u), static_cast<std::uint8_t>(r));
        } else {
          ++counters_.dropped_points;
          ++dropped_points_;
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
  // A partial frame's missing columns are mostly those before it began: not lost.
  const unsigned lost_packets = whole_ ? (missing + per_packet - 1) / per_packet : 0;
  counters_.lost_packets += lost_packets;
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
  frame.lost_packets = lost_packets;
  frame.dropped_points = static_cast<std::uint32_t>(std::min<std::uint64_t>(dropped_points_, std::numeric_limits<std::uint32_t>::max()));
  frame.missing_columns = missing;
  frame.invalid_columns = invalid_columns_;
  frame.whole = whole_;
  attached_ = false;  // the span is the caller's until the next set_output
  ++counters_.frames;
  return frame;
}

}  // namespace sim::ouster
