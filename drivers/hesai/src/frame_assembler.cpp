// SPDX-License-Identifier: Apache-2.0
// Point formula (docs/hesai.md, "Sensor frame"): x = d·cos(el)·sin(az), y = d·cos(el)·cos(az),
// z = d·sin(el), az = block azimuth + channel azimuth offset. The multi-return filters and the
// per-point cut follow nebula's decoder so its reference clouds are reproduced exactly
// (tests/drivers/hesai/data/NOTICE.md: how they were made).
#include "sim/hesai/frame_assembler.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

namespace sim::hesai {
namespace {

constexpr unsigned full_turn = 36000;  // 0.01°
// A firing group up to this far behind the previous one is a reordered or repeated packet,
// not a new revolution.
constexpr unsigned reorder_window = 1000;
// Sequence jumps larger than this are a sensor restart, not loss.
constexpr std::uint32_t max_counted_loss = 100000;
// Channel azimuth offsets are a few degrees; a spread this large is not a calibration.
constexpr double max_offset_spread_deg = 90.0;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// Severity order of the functional-safety states: initialization and warning still deliver
// trusted points, degradation less so, untrusted output not at all.
int severity(LidarState state) noexcept {
  switch (state) {
    case LidarState::normal: return 0;
    case LidarState::initialization: return 1;
    case LidarState::warning: return 2;
    case LidarState::performance_degradation: return 3;
    case LidarState::output_untrusted: return 4;
  }
  return 4;
}
bool worse(LidarState a, LidarState b) noexcept { return severity(a) > severity(b); }

// One firing group (one firing of every channel, up to three returns) decoded into one array
// per quantity, so that each quantity is computed by a plain loop over channels (see
// decode_group). About 13 KiB, on the stack.
constexpr unsigned group_channels = 128;
constexpr unsigned group_returns = 3;
struct GroupScratch {
  template <typename T>
  using PerReturn = std::array<std::array<T, group_channels>, group_returns>;
  PerReturn<std::uint16_t> raw;
  PerReturn<std::uint8_t> reflectivity;
  PerReturn<float> distance;
  PerReturn<std::uint8_t> keep;  // 1: the point passes every filter
  // Each point's first 16 bytes (x, y, z, intensity) and last 8 (time offset, ring, return
  // index, reserved) as they lie in a LidarPoint: copying a kept point is then two moves.
  struct Xyzi {
    float x, y, z, intensity;
  };
  PerReturn<Xyzi> xyzi;
  PerReturn<std::uint64_t> tail;
  std::array<float, group_channels> sin_az;
  std::array<float, group_channels> cos_az;
};
static_assert(sizeof(GroupScratch::Xyzi) == offsetof(LidarPoint, time_offset_ns) &&
              sizeof(LidarPoint) == sizeof(GroupScratch::Xyzi) + sizeof(std::uint64_t));
// The tail word is built with shifts: time offset in the low bytes, as in memory on the
// little-endian CPUs SIM runs on (x86-64, aarch64).
static_assert(std::endian::native == std::endian::little);
std::uint64_t point_tail(std::uint32_t time_offset_ns, unsigned ring,
                         unsigned return_index) noexcept {
  return std::uint64_t{time_offset_ns} | std::uint64_t{ring} << 32 |
         std::uint64_t{return_index} << 48;
}

// The unit size (3 or 4 bytes) as a constant, so the loop reads at a fixed stride instead of
// multiplying by a runtime value per channel.
template <std::size_t unit_size>
void read_units(const std::uint8_t* units, unsigned channels, std::uint16_t* raw,
                std::uint8_t* reflectivity) noexcept {
  unsigned ch = 0;
  if constexpr (unit_size == 3) {
    // 3-byte units do not vectorize without byte shuffles (SSSE3, not in baseline x86-64):
    // four channels at a time from three 32-bit words instead, 3 loads and 2 stores for what
    // is 8 loads and 8 stores one channel at a time.
    for (; ch + 4 <= channels; ch += 4) {
      std::uint32_t w[3];
      std::memcpy(w, units + ch * 3, sizeof w);
      const std::uint64_t r4 = std::uint64_t{w[0] & 0xFFFF} |
                               std::uint64_t{(w[0] >> 24) | ((w[1] & 0xFF) << 8)} << 16 |
                               std::uint64_t{w[1] >> 16} << 32 |
                               std::uint64_t{(w[2] >> 8) & 0xFFFF} << 48;
      const std::uint32_t f4 = ((w[0] >> 16) & 0xFF) | (w[1] & 0xFF00) |
                               (w[2] & 0xFF) << 16 | (w[2] & 0xFF00'0000);
      std::memcpy(raw + ch, &r4, sizeof r4);
      std::memcpy(reflectivity + ch, &f4, sizeof f4);
    }
  }
  for (; ch < channels; ++ch) {
    const std::uint8_t* unit = units + ch * unit_size;
    raw[ch] = static_cast<std::uint16_t>(unit[0] | (unit[1] << 8));
    reflectivity[ch] = unit[2];
  }
}

// What pass 1 reads: the group's blocks (one per return) and the assembler's per-channel
// tables and options.
struct GroupInput {
  std::array<const std::uint8_t*, group_returns> units;  // Packet::units of each return's block
  unsigned unit_size;
  unsigned channels;
  float sin_block;
  float cos_block;
  float distance_unit_m;
  float min_range_m;
  float max_range_m;
  float threshold_m;
  bool drop_zero;
  bool drop_identical;
  const float* cos_elevation;
  const float* sin_elevation;
  const float* cos_azimuth_offset;
  const float* sin_azimuth_offset;
};

// Return pairing, as nebula filters multi-return groups: a return other than the last is
// dropped when another return of its channel has the same distance and reflectivity (one echo
// reported twice) or lies within `threshold` of it; the last return is never dropped here.
template <unsigned returns>
void drop_duplicate_returns(GroupScratch& g, unsigned n, float threshold,
                            bool drop_identical) noexcept {
  for (unsigned r = 0; r + 1 < returns; ++r) {
    for (unsigned other = 0; other < returns; ++other) {
      if (other == r) continue;
      for (unsigned ch = 0; ch < n; ++ch) {
        // Bitwise on 0/1 values, not && and ||: no branch in the loop.
        const unsigned identical = unsigned{drop_identical} &
                                   unsigned{g.raw[other][ch] == g.raw[r][ch]} &
                                   unsigned{g.reflectivity[other][ch] == g.reflectivity[r][ch]};
        const unsigned close =
            unsigned{std::fabs(g.distance[other][ch] - g.distance[r][ch]) < threshold};
        g.keep[r][ch] = static_cast<std::uint8_t>(g.keep[r][ch] & ~(identical | close) & 1u);
      }
    }
  }
}

// Pass 1 of decode_group: every point of the group, kept or not, one quantity at a time in
// loops with no branch and no call, which the compiler turns into SIMD code. The float
// operations are the same, in the same order, as for one point at a time, so the results are
// bit for bit those of the scalar formula. `returns` is a constant so the loops over returns
// unroll.
template <unsigned returns>
void compute_points(const GroupInput& in, GroupScratch& g) noexcept {
  // Locals, not reads through `in`: the compiler cannot prove that the stores into `g` leave
  // `in` unchanged, and would reload every field inside the loops instead of vectorizing them.
  const unsigned n = in.channels;
  const float sin_block = in.sin_block;
  const float cos_block = in.cos_block;
  const float unit = in.distance_unit_m;
  const float min_range = in.min_range_m;
  const float max_range = in.max_range_m;
  const float threshold = in.threshold_m;
  const bool drop_zero = in.drop_zero;
  const bool drop_identical = in.drop_identical;
  const float* const cos_elevation = in.cos_elevation;
  const float* const sin_elevation = in.sin_elevation;
  const float* const cos_azimuth_offset = in.cos_azimuth_offset;
  const float* const sin_azimuth_offset = in.sin_azimuth_offset;

  for (unsigned r = 0; r < returns; ++r) {
    if (in.unit_size == 4) {
      read_units<4>(in.units[r], n, g.raw[r].data(), g.reflectivity[r].data());
    } else {
      read_units<3>(in.units[r], n, g.raw[r].data(), g.reflectivity[r].data());
    }
  }
  // Each channel's direction: the block azimuth turned by the channel's azimuth offset.
  for (unsigned ch = 0; ch < n; ++ch) {
    g.sin_az[ch] = sin_block * cos_azimuth_offset[ch] + cos_block * sin_azimuth_offset[ch];
    g.cos_az[ch] = cos_block * cos_azimuth_offset[ch] - sin_block * sin_azimuth_offset[ch];
  }
  // The filters, as nebula applies them: no return, out of range, then return pairing.
  for (unsigned r = 0; r < returns; ++r) {
    for (unsigned ch = 0; ch < n; ++ch) {
      const float distance = static_cast<float>(g.raw[r][ch]) * unit;
      g.distance[r][ch] = distance;
      g.keep[r][ch] = static_cast<std::uint8_t>(unsigned{g.raw[r][ch] != 0 || !drop_zero} &
                                                unsigned{!(distance < min_range)} &
                                                unsigned{!(distance > max_range)});
    }
  }
  drop_duplicate_returns<returns>(g, n, threshold, drop_identical);
  for (unsigned r = 0; r < returns; ++r) {
    for (unsigned ch = 0; ch < n; ++ch) {
      const float distance = g.distance[r][ch];
      const float horizontal = distance * cos_elevation[ch];
      g.xyzi[r][ch] = {horizontal * g.sin_az[ch], horizontal * g.cos_az[ch],
                       distance * sin_elevation[ch], static_cast<float>(g.reflectivity[r][ch])};
    }
  }
}

// Pass 2 of decode_group, common case: the whole group goes to one frame whose storage has
// room for every point of it. Each point is written unconditionally at the end of the frame
// and the end moves on only for a kept one: no branch to mispredict on the data. (A point
// written but not kept lies past the frame's point count, in storage the frame owns, and is
// overwritten by the next one.) Returns the number of points kept.
template <unsigned returns>
std::size_t copy_kept_points(GroupScratch& g, unsigned n, std::uint32_t time_base,
                             const std::int32_t* channel_offset_ns, LidarPoint* out) noexcept {
  for (unsigned r = 0; r < returns; ++r) {
    for (unsigned ch = 0; ch < n; ++ch) {
      // The caller checked that base + offset lies in [0, 2^32): modulo 2^32 is exact.
      g.tail[r][ch] =
          point_tail(time_base + static_cast<std::uint32_t>(channel_offset_ns[ch]), ch, r);
    }
  }
  auto* bytes = reinterpret_cast<std::byte*>(out);
  std::size_t count = 0;
  for (unsigned ch = 0; ch < n; ++ch) {
    for (unsigned r = 0; r < returns; ++r) {
      std::byte* point = bytes + count * sizeof(LidarPoint);
      std::memcpy(point, &g.xyzi[r][ch], sizeof(GroupScratch::Xyzi));
      std::memcpy(point + sizeof(GroupScratch::Xyzi), &g.tail[r][ch], sizeof(std::uint64_t));
      count += g.keep[r][ch];
    }
  }
  return count;
}

// The return count as the constant compute_points and copy_kept_points are instantiated for.
void compute_group_points(const GroupInput& in, unsigned returns, GroupScratch& g) noexcept {
  switch (returns) {
    case 1: compute_points<1>(in, g); break;
    case 2: compute_points<2>(in, g); break;
    default: compute_points<3>(in, g); break;
  }
}
std::size_t copy_group_points(GroupScratch& g, unsigned n, unsigned returns,
                              std::uint32_t time_base, const std::int32_t* channel_offset_ns,
                              LidarPoint* out) noexcept {
  switch (returns) {
    case 1: return copy_kept_points<1>(g, n, time_base, channel_offset_ns, out);
    case 2: return copy_kept_points<2>(g, n, time_base, channel_offset_ns, out);
    default: return copy_kept_points<3>(g, n, time_base, channel_offset_ns, out);
  }
}

// Which frame a channel's points go to, as an index into GroupSinks::of.
enum FrameTarget : std::uint8_t { to_current = 0, to_next = 1, to_nowhere = 2 };

// How the group's points are stamped: the group's firing time relative to the stamp of the
// current and of the next frame, plus each channel's firing offset in the group's firing loop,
// whose range tells at once whether every point's offset fits its uint32 unclamped.
struct GroupTimes {
  std::array<std::int64_t, 2> base;
  const std::int32_t* channel_offset_ns;
  std::int32_t min_channel_offset_ns;
  std::int32_t max_channel_offset_ns;
};

}  // namespace

namespace detail {

struct GroupTargets {
  std::array<std::uint8_t, group_channels> of_channel{};  // FrameTarget of each channel
  bool one_frame = true;  // every channel goes where channel 0 goes
};

// Where one frame's points go during one group: its storage and count, copied into locals so
// the hot loops do not re-read members (FrameAssembler::store_sinks writes them back).
struct PointSink {
  LidarPoint* out = nullptr;
  std::size_t capacity = 0;
  std::size_t count = 0;
  std::uint32_t dropped = 0;  // kept points that found no room
  bool active = false;        // the group has points for this frame and it is open
};
struct GroupSinks {
  // Indexed by FrameTarget; to_nowhere's sink is never active, so a point's target indexes
  // the array without a test.
  std::array<PointSink, 3> of{};
};

}  // namespace detail

namespace {

// Pass 2 near the cut, in a frame's nearly full storage or after a clock jump: point by point,
// each to its own channel's frame, with the time offset clamped and a point that finds no
// room counted as dropped.
void write_points_one_by_one(const GroupScratch& g, unsigned n, unsigned returns,
                             const detail::GroupTargets& targets, const GroupTimes& times,
                             detail::GroupSinks& sinks) noexcept {
  for (unsigned ch = 0; ch < n; ++ch) {
    const std::uint8_t target = targets.of_channel[ch];
    detail::PointSink& sink = sinks.of[target];
    if (!sink.active) continue;
    // Offsets are ≥ 0 by the stamp's choice; clamped only against a clock that jumps.
    const auto time_offset = static_cast<std::uint32_t>(
        std::clamp<std::int64_t>(times.base[target] + times.channel_offset_ns[ch], 0,
                                 std::numeric_limits<std::uint32_t>::max()));
    for (unsigned r = 0; r < returns; ++r) {
      if (!g.keep[r][ch]) continue;
      if (sink.count >= sink.capacity) {
        ++sink.dropped;
        continue;
      }
      const GroupScratch::Xyzi& p = g.xyzi[r][ch];
      sink.out[sink.count++] = LidarPoint{p.x,
                                          p.y,
                                          p.z,
                                          p.intensity,
                                          time_offset,
                                          static_cast<std::uint16_t>(ch),
                                          static_cast<std::uint8_t>(r),
                                          0};
    }
  }
}

// Pass 2 of decode_group: the kept points, in channel then return order, into their frame's
// storage. Common case: the whole group goes to one frame, its storage has room for every
// point of the group, and every time offset fits without the clamp; then copy_kept_points
// writes them without a branch on the data.
void write_kept_points(GroupScratch& g, unsigned n, unsigned returns,
                       const detail::GroupTargets& targets, const GroupTimes& times,
                       detail::GroupSinks& sinks) noexcept {
  const std::uint8_t target = targets.of_channel[0];
  if (targets.one_frame && target != to_nowhere) {
    detail::PointSink& sink = sinks.of[target];
    const std::int64_t base = times.base[target];
    if (sink.active && sink.capacity - sink.count >= std::size_t{n} * returns &&
        base + times.min_channel_offset_ns >= 0 &&
        base + times.max_channel_offset_ns <=
            std::int64_t{std::numeric_limits<std::uint32_t>::max()}) {
      // Base + offset lies in [0, 2^32): the sum modulo 2^32 is the exact value.
      sink.count += copy_group_points(g, n, returns, static_cast<std::uint32_t>(base),
                                      times.channel_offset_ns, sink.out + sink.count);
      return;
    }
  }
  write_points_one_by_one(g, n, returns, targets, times, sinks);
}

}  // namespace

Expected<FrameAssembler> FrameAssembler::create(Calibration calibration,
                                                AssemblerOptions options) {
  const ModelInfo& m = info(options.model);
  const std::string model_name(to_string(options.model));
  if (calibration.channels() != m.channels) {
    return invalid("the calibration has " + std::to_string(calibration.channels()) +
                   " channels but a " + model_name + " has " + std::to_string(m.channels) +
                   "; use the calibration file of this sensor or set the right model");
  }
  if (options.firetimes && options.firetimes->channels() != m.channels) {
    return invalid("the firing-time file has " + std::to_string(options.firetimes->channels()) +
                   " channels but a " + model_name + " has " + std::to_string(m.channels) +
                   "; use Hesai's firing-time file for this model");
  }
  if (options.firetimes && options.model == Model::pandar_qt128) {
    return invalid("a firing-time file cannot describe the PandarQT128's two firing loops; leave "
                   "--firetimes out (its firing times are built in)");
  }
  float lowest = 0, highest = 0;
  for (const auto& a : calibration.angles()) {
    if (!std::isfinite(a.azimuth_offset_deg) || !std::isfinite(a.elevation_deg)) {
      return invalid("the calibration holds a non-finite angle; use the sensor's own file");
    }
    lowest = std::min(lowest, a.azimuth_offset_deg);
    highest = std::max(highest, a.azimuth_offset_deg);
  }
  if (highest - lowest > max_offset_spread_deg) {
    return invalid("the calibration's azimuth offsets spread over more than 90 degrees, which "
                   "no Hesai sensor has; check that the columns are channel,elevation,azimuth");
  }
  const float min_range = options.min_range_m.value_or(m.min_range_m);
  const float max_range = options.max_range_m.value_or(m.max_range_m);
  if (!std::isfinite(min_range) || !std::isfinite(max_range) || min_range < 0 ||
      max_range <= min_range) {
    return invalid("the range limits must satisfy 0 <= minimum < maximum, got " +
                   std::to_string(min_range) + " to " + std::to_string(max_range) + " m");
  }
  if (!std::isfinite(options.multi_return_distance_threshold_m) ||
      options.multi_return_distance_threshold_m < 0) {
    return invalid("the multi-return distance threshold must be 0 (off) or a positive distance");
  }
  if (!std::isfinite(options.cut_azimuth_deg)) {
    return invalid("the cut azimuth must be an angle in degrees, e.g. 0 or 180");
  }
  return FrameAssembler(std::move(calibration), std::move(options));
}

FrameAssembler::FrameAssembler(Calibration calibration, AssemblerOptions options)
    : calibration_(std::move(calibration)), options_(std::move(options)) {
  const ModelInfo& m = info(options_.model);
  channels_ = m.channels;
  min_range_m_ = options_.min_range_m.value_or(m.min_range_m);
  max_range_m_ = options_.max_range_m.value_or(m.max_range_m);
  double cut = std::fmod(options_.cut_azimuth_deg, 360.0);
  if (cut < 0) cut += 360.0;
  cut_centi_deg_ = static_cast<std::uint16_t>(std::lround(cut * 100.0) % full_turn);

  constexpr double deg = std::numbers::pi / 180.0;
  earliest_channel_offset_ns_ = std::numeric_limits<std::int32_t>::max();
  min_channel_offset_ns_.fill(std::numeric_limits<std::int32_t>::max());
  max_channel_offset_ns_.fill(std::numeric_limits<std::int32_t>::min());
  for (unsigned ch = 0; ch < channels_; ++ch) {
    const double elevation = calibration_[ch].elevation_deg * deg;
    cos_elevation_[ch] = static_cast<float>(std::cos(elevation));
    sin_elevation_[ch] = static_cast<float>(std::sin(elevation));
    for (unsigned loop = 0; loop < 2; ++loop) {
      std::int32_t offset = Packet::channel_offset_ns(options_.model, ch, loop);
      if (options_.firetimes) {
        // Hesai's file has the same meaning as the built-in tables, except QT64 whose table
        // adds 10 µs to the file's values (reference §5).
        const double extra = options_.model == Model::pandar_qt64 ? 10000.0 : 0.0;
        offset = static_cast<std::int32_t>(std::lround((*options_.firetimes)[ch] * 1000.0 + extra));
      }
      channel_offset_ns_[loop][ch] = offset;
      earliest_channel_offset_ns_ = std::min(earliest_channel_offset_ns_, offset);
      min_channel_offset_ns_[loop] = std::min(min_channel_offset_ns_[loop], offset);
      max_channel_offset_ns_[loop] = std::max(max_channel_offset_ns_[loop], offset);
    }
  }
  update_azimuth_offsets(0);

  // The carry-over holds the next frame's points from the first firing whose points cross the
  // cut until the driver's next set_output(): the offset spread in firing groups (at half the
  // 10 Hz step, for 5 Hz operation) plus two packets, at up to three returns.
  const double spread = max_cut_offset_centi_ - min_cut_offset_centi_;
  const auto overlap_groups =
      static_cast<std::size_t>(std::ceil(spread / (m.azimuth_step_10hz / 2.0))) + 1;
  out_.reserve_carry((overlap_groups + 2 * std::size_t{m.blocks_per_packet}) * m.channels * 3);
}

void FrameAssembler::update_azimuth_offsets(std::uint16_t rpm) noexcept {
  constexpr double deg = std::numbers::pi / 180.0;
  const bool compensate = options_.firetimes && options_.firetime_azimuth_compensation;
  min_cut_offset_centi_ = 0;
  max_cut_offset_centi_ = 0;
  for (unsigned ch = 0; ch < channels_; ++ch) {
    double offset = calibration_[ch].azimuth_offset_deg;
    // The laser fires firetime µs after the block time, while the head turns rpm·6e-6 °/µs.
    if (compensate) offset += (*options_.firetimes)[ch] * rpm * 6e-6;
    cos_azimuth_offset_[ch] = static_cast<float>(std::cos(offset * deg));
    sin_azimuth_offset_[ch] = static_cast<float>(std::sin(offset * deg));
    cut_offset_centi_[ch] = options_.cut_by == CutBy::point_azimuth ? offset * 100.0 : 0.0;
    min_cut_offset_centi_ = std::min(min_cut_offset_centi_, cut_offset_centi_[ch]);
    max_cut_offset_centi_ = std::max(max_cut_offset_centi_, cut_offset_centi_[ch]);
  }
  compensated_rpm_ = rpm;
}

std::size_t FrameAssembler::pending_points() const noexcept { return out_.pending(); }

std::optional<std::int64_t> FrameAssembler::time_to_cut_ns() const noexcept {
  if (!have_last_ || last_rpm_ == 0) return std::nullopt;
  // push() completes the frame once a group's position + min_cut_offset reaches its end.
  const double position = static_cast<double>(block_revolution_) * full_turn + last_phase_;
  const double end = static_cast<double>(current_revolution_ + 1) * full_turn;
  const double centi_degrees = end - min_cut_offset_centi_ - position;
  if (centi_degrees <= 0) return 0;
  // rpm · 6 degrees per second.
  return static_cast<std::int64_t>(centi_degrees / 100.0 / (last_rpm_ * 6.0) * 1e9);
}

void FrameAssembler::set_output(std::span<LidarPoint> output) noexcept {
  // Replaced in the middle of a frame, its points so far stay in the old span (lost to it) and
  // the carry-over keeps the next frame's; else the carry-over moves to the span's front.
  const lidar::FrameOutput::Attached attached = out_.attach(output);
  if (attached.lost > 0) current_.whole = false;
  drop_points(current_, attached.lost + attached.did_not_fit);
}

void FrameAssembler::drop_points(FrameState& frame, std::size_t points) noexcept {
  frame.dropped += static_cast<std::uint32_t>(points);
  counters_.dropped_points += points;
}

void FrameAssembler::reset() noexcept {
  current_ = FrameState{};
  next_ = FrameState{};
  out_.clear();
  have_last_ = false;
  azimuth_step_ = 0;
  have_sequence_ = false;
}

void FrameAssembler::close_current(PushResult& result, bool ended_at_cut) noexcept {
  if (current_.started) {
    if (!current_.whole && !options_.emit_partial_frames && ended_at_cut) {
      ++counters_.partial_frames_dropped;  // its points go below
    } else if (out_.attached()) {
      CompletedFrame& frame = result.frame.emplace();
      frame.point_count = out_.output_count();
      frame.stamp_ns = current_.stamp_ns;
      frame.host_receive_ns = current_.host_ns;
      frame.index = frame_index_++;
      frame.packets = current_.packets;
      frame.lost_packets = current_.lost;
      frame.dropped_points = current_.dropped;
      frame.whole = current_.whole && ended_at_cut;
      frame.motor_rpm = current_.rpm;
      frame.safety = current_.safety;
      ++counters_.frames;
      // The span now belongs to the caller; the next frame's points are in the carry-over.
      out_.hand_out();
      current_ = next_;
      next_ = FrameState{};
      return;
    } else {
      // Completed while the caller still holds the previous frame: nowhere to put it.
      ++counters_.frames_without_output;
    }
  }
  // No frame handed out: the next frame takes over the storage the current one had. A partial
  // frame's points in the span are not counted as dropped (the frame is, as
  // partial_frames_dropped); points that never had a span are.
  const bool had_span = out_.attached();
  const lidar::FrameOutput::Advanced advanced = out_.advance();
  if (!had_span) counters_.dropped_points += advanced.discarded;
  current_ = next_;
  next_ = FrameState{};
  drop_points(current_, advanced.did_not_fit);
}

std::optional<CompletedFrame> FrameAssembler::finish() noexcept {
  PushResult result;
  if (next_.started) {
    // The next frame's few points cannot be kept apart from the finished one.
    counters_.dropped_points += out_.drop_next();
    next_ = FrameState{};
  }
  close_current(result, false);
  current_ = FrameState{};
  have_last_ = false;
  return result.frame;
}

void FrameAssembler::begin(FrameState& frame, const Packet& packet, unsigned block,
                           std::int64_t host_ns, bool whole) noexcept {
  frame = FrameState{};
  frame.started = true;
  frame.whole = whole;
  // The frame's stamp is the earliest firing of its first group, so point offsets are ≥ 0.
  frame.stamp_ns = packet.time_ns() + packet.block_offset_ns(block) + earliest_channel_offset_ns_;
  frame.host_ns = host_ns;
  frame.last_packet = 0;
}

void FrameAssembler::count_loss(const Packet& packet) noexcept {
  if (const auto sequence = packet.sequence()) {
    if (have_sequence_) {
      const std::uint32_t ahead = *sequence - last_sequence_;  // modulo 2^32
      if (ahead == 0 || ahead > 0x8000'0000u) {
        ++counters_.out_of_order;
        if (ahead != 0 && ~ahead + 1 < reorder_window) return;  // a late packet: keep position
      } else if (ahead - 1 <= max_counted_loss) {
        counters_.lost_packets += ahead - 1;
        current_.lost += ahead - 1;
      }
    }
    have_sequence_ = true;
    last_sequence_ = *sequence;
    return;
  }
  // No sequence (Pandar40P/64 without it): a gap between the last firing of the previous packet
  // and the first of this one, in units of the packet's azimuth span.
  const unsigned groups = packet.blocks() / packet.returns();
  if (have_last_ && azimuth_step_ > 0) {
    const unsigned gap = (packet.azimuth(0) + full_turn - last_azimuth_) % full_turn;
    if (gap < full_turn / 2 && gap * 2 > azimuth_step_ * 3u) {
      const double per_packet = static_cast<double>(azimuth_step_) * groups;
      const auto missing =
          static_cast<std::uint32_t>(std::lround((gap - azimuth_step_) / per_packet));
      counters_.lost_packets += missing;
      current_.lost += missing;
    }
  }
  if (groups > 1) {
    const unsigned span =
        (packet.azimuth((groups - 1) * packet.returns()) + full_turn - packet.azimuth(0)) %
        full_turn;
    azimuth_step_ = static_cast<std::uint16_t>(span / (groups - 1));
  }
}

// The per-group steps of push() and decode_group() below are defined `inline` (they are
// private and used only in this file) so that GCC inlines them as it did when they were one
// long function: called out of line they cost about 0.7 % more instructions per QT128 packet
// (callgrind on bench_hesai_decode).
PushResult FrameAssembler::push(std::span<const std::uint8_t> payload,
                                std::int64_t host_receive_ns) noexcept {
  PushResult result;
  Packet packet;
  result.error = Packet::parse(payload, options_.model, packet);
  if (result.error != PacketError::none) {
    count_rejected(result.error);
    return result;
  }
  ++counters_.packets;
  ++packet_counter_;
  result.packet_ns = packet.time_ns();
  last_rpm_ = packet.motor_rpm();
  last_safety_ = packet.functional_safety();
  count_loss(packet);
  if (options_.firetimes && options_.firetime_azimuth_compensation &&
      packet.motor_rpm() != compensated_rpm_) {
    update_azimuth_offsets(packet.motor_rpm());
  }

  const unsigned returns = packet.returns();
  for (unsigned block = 0; block < packet.blocks(); block += returns) {
    const std::uint16_t azimuth = packet.azimuth(block);
    const auto phase =
        static_cast<std::uint16_t>((azimuth + full_turn - cut_centi_deg_) % full_turn);
    const std::int64_t group_revolution = revolution_of_group(azimuth, phase);
    close_frame_before(packet, block, group_revolution, phase, host_receive_ns, result);
    decode_group(packet, block, group_revolution, phase, host_receive_ns);
  }
  return result;
}

void FrameAssembler::count_rejected(PacketError error) noexcept {
  ++counters_.rejected[static_cast<std::size_t>(error)];
  if (error == PacketError::wrong_model) {
    ++counters_.wrong_model;
  } else if (error == PacketError::bad_crc) {
    ++counters_.crc_errors;
  } else {
    ++counters_.malformed;
  }
}

// Which revolution a firing group belongs to, counted by the block azimuth wrapping at the
// cut. `phase` is the azimuth relative to the cut.
inline std::int64_t FrameAssembler::revolution_of_group(std::uint16_t azimuth,
                                                 std::uint16_t phase) noexcept {
  if (!have_last_) {
    // Joining mid-revolution (start, reset, finish): the frame in progress is partial.
    block_revolution_ = 0;
    current_revolution_ = 0;
    current_ = FrameState{};
    next_ = FrameState{};
    have_last_ = true;
    last_phase_ = phase;
    last_azimuth_ = azimuth;
    return 0;
  }
  const unsigned forward = (phase + full_turn - last_phase_) % full_turn;
  if (forward > full_turn - reorder_window) {
    // A late packet: decode it where it belongs without moving the cut state.
    return phase > last_phase_ ? block_revolution_ - 1 : block_revolution_;
  }
  if (phase < last_phase_) ++block_revolution_;
  last_phase_ = phase;
  last_azimuth_ = azimuth;
  return block_revolution_;
}

// The current frame is complete once no channel of this group can still fall in it: it is
// closed (handed out in `result` when it has a span) and the next one takes its place.
inline void FrameAssembler::close_frame_before(const Packet& packet, unsigned block,
                                        std::int64_t group_revolution, std::uint16_t phase,
                                        std::int64_t host_ns, PushResult& result) noexcept {
  const double position = static_cast<double>(group_revolution) * full_turn + phase;
  const double current_end = static_cast<double>(current_revolution_ + 1) * full_turn;
  if (position + min_cut_offset_centi_ < current_end) return;
  // A second completion in one packet (only a corrupt stream can do that) finds no span
  // attached and is counted as frames_without_output by close_current.
  PushResult closed;
  close_current(closed, true);
  if (closed.frame && !result.frame) result.frame = closed.frame;
  ++current_revolution_;
  // With no point across the cut yet (cutting by block), the new frame starts here.
  if (!current_.started) begin(current_, packet, block, host_ns, true);
  if (position + min_cut_offset_centi_ >= current_end + full_turn) {
    // A gap of more than a revolution: restart from this group.
    current_revolution_ = group_revolution;
    current_ = FrameState{};
    next_ = FrameState{};
    out_.clear();
  }
}

void FrameAssembler::decode_group(const Packet& packet, unsigned first_block,
                                  std::int64_t group_revolution, std::uint16_t phase,
                                  std::int64_t host_ns) noexcept {
  const detail::GroupTargets targets = frames_of_channels(phase, group_revolution);
  detail::GroupSinks sinks = open_sinks(targets, packet, first_block, host_ns);
  // Every point of the group belongs to a frame already handed out.
  if (!sinks.of[to_current].active && !sinks.of[to_next].active) return;

  // Pass 1: every point of the group, kept or not, one quantity at a time (see GroupScratch).
  // The block azimuth's sine and cosine are the group's only trigonometry: each channel's
  // direction is this one turned by its precomputed azimuth offset.
  const unsigned n = channels_;
  const unsigned returns = packet.returns();
  const double azimuth_rad = packet.azimuth(first_block) * (std::numbers::pi / 18000.0);
  GroupInput input{{},
                   packet.unit_size(),
                   n,
                   static_cast<float>(std::sin(azimuth_rad)),
                   static_cast<float>(std::cos(azimuth_rad)),
                   packet.distance_unit_m(),
                   min_range_m_,
                   max_range_m_,
                   options_.multi_return_distance_threshold_m,
                   options_.drop_zero_distance,
                   options_.drop_identical_returns,
                   cos_elevation_.data(),
                   sin_elevation_.data(),
                   cos_azimuth_offset_.data(),
                   sin_azimuth_offset_.data()};
  for (unsigned r = 0; r < returns; ++r) input.units[r] = packet.units(first_block + r);
  GroupScratch g;  // not zeroed: each loop writes the [returns][n] part the next ones read
  compute_group_points(input, returns, g);

  // Pass 2: the kept points into their frames, stamped relative to each frame's stamp.
  const std::int64_t group_time = packet.time_ns() + packet.block_offset_ns(first_block);
  const unsigned loop = packet.firing_loop(first_block);
  const GroupTimes times{{group_time - current_.stamp_ns, group_time - next_.stamp_ns},
                         channel_offset_ns_[loop].data(),
                         min_channel_offset_ns_[loop],
                         max_channel_offset_ns_[loop]};
  write_kept_points(g, n, returns, targets, times, sinks);
  store_sinks(sinks);
}

// A point belongs to the revolution its own azimuth falls in: the group's, unless the
// channel's cut offset (its azimuth offset, when cutting by point) carries it across the cut.
// Points of a revolution other than the current one or the next go nowhere: late points of a
// frame already handed out.
inline detail::GroupTargets FrameAssembler::frames_of_channels(
    std::uint16_t phase, std::int64_t group_revolution) const noexcept {
  auto target_of = [this](std::int64_t revolution) -> std::uint8_t {
    if (revolution == current_revolution_) return to_current;
    if (revolution == current_revolution_ + 1) return to_next;
    return to_nowhere;
  };
  static_assert(group_channels >= max_channels);
  detail::GroupTargets targets;
  // Common case: every channel of the group falls in the same revolution.
  const bool straddles =
      phase + min_cut_offset_centi_ < 0 || phase + max_cut_offset_centi_ >= full_turn;
  if (!straddles) {
    std::fill_n(targets.of_channel.begin(), channels_, target_of(group_revolution));
    return targets;
  }
  for (unsigned ch = 0; ch < channels_; ++ch) {
    const double point_phase = phase + cut_offset_centi_[ch];
    std::int64_t revolution = group_revolution;
    if (point_phase < 0) --revolution;
    if (point_phase >= full_turn) ++revolution;
    targets.of_channel[ch] = target_of(revolution);
  }
  const std::uint8_t first = targets.of_channel[0];
  const auto end = targets.of_channel.begin() + channels_;
  targets.one_frame = std::all_of(targets.of_channel.begin(), end,
                                  [first](std::uint8_t t) { return t == first; });
  return targets;
}

// Opens the frames the group has points for (a frame starts at its first group) and points a
// sink at each one's storage: the current frame's is the caller's span once attached, the
// carry-over before; the next frame's is the carry-over, or nothing while the carry-over
// still holds the current frame.
inline detail::GroupSinks FrameAssembler::open_sinks(const detail::GroupTargets& targets,
                                              const Packet& packet, unsigned first_block,
                                              std::int64_t host_ns) noexcept {
  bool used[2] = {false, false};
  const unsigned distinct = targets.one_frame ? 1 : channels_;
  for (unsigned ch = 0; ch < distinct; ++ch) {
    if (targets.of_channel[ch] != to_nowhere) used[targets.of_channel[ch]] = true;
  }
  detail::GroupSinks sinks;
  if (used[to_current]) {
    if (!current_.started) begin(current_, packet, first_block, host_ns, false);
    detail::PointSink& s = sinks.of[to_current];
    s.active = true;
    const lidar::FrameOutput::Storage storage = out_.current();
    s.out = storage.data;
    s.capacity = storage.capacity;
    s.count = storage.count;
    note_packet(current_, packet);
  }
  if (used[to_next]) {
    if (!next_.started) begin(next_, packet, first_block, host_ns, true);
    detail::PointSink& s = sinks.of[to_next];
    s.active = true;
    if (out_.attached()) {
      const lidar::FrameOutput::Storage storage = out_.next();
      s.out = storage.data;
      s.capacity = storage.capacity;
      s.count = storage.count;
    } else {
      // The carry-over still holds the current frame (no span yet): the next one loses
      // these points and is not a whole revolution.
      next_.whole = false;
    }
    note_packet(next_, packet);
  }
  return sinks;
}

// A packet counts once in each frame it gives points to, however many of its groups do.
inline void FrameAssembler::note_packet(FrameState& frame, const Packet& packet) noexcept {
  if (frame.last_packet == packet_counter_) return;
  frame.last_packet = packet_counter_;
  ++frame.packets;
  frame.rpm = packet.motor_rpm();
  if (const auto safety = packet.functional_safety()) {
    if (!frame.safety || worse(safety->state, frame.safety->state)) frame.safety = safety;
  }
}

// Writes the sinks' counts back where they live, and their drops into the frame and counters.
inline void FrameAssembler::store_sinks(const detail::GroupSinks& sinks) noexcept {
  const detail::PointSink& current = sinks.of[to_current];
  const detail::PointSink& next = sinks.of[to_next];
  if (current.active) out_.set_current_count(current.count);
  if (next.active) out_.set_next_count(next.count);
  FrameState* const frames[2] = {&current_, &next_};
  for (unsigned t = 0; t < 2; ++t) {
    if (sinks.of[t].active) {
      frames[t]->dropped += sinks.of[t].dropped;
      counters_.dropped_points += sinks.of[t].dropped;
    }
  }
}

}  // namespace sim::hesai
