// SPDX-License-Identifier: Apache-2.0
// Decoding (docs/velodyne.md has the formulas and their sources):
//   distance  d = raw · unit + dist_correction                       (unit from the model)
//   azimuth   a = block azimuth + step · fraction(laser) − rot_correction, rounded to 0.01°
//             (fraction: the laser's firing time over the sequence, from the manual's table)
//   ROS frame x = d·cos(vert)·cos(a), y = −d·cos(vert)·sin(a), z = d·sin(vert)
// with the HDL-64E's offsets and two-point correction where the calibration has them. The
// 0.01° rounding is what nebula and ros-drivers/velodyne do (36,000-entry sin/cos tables): a
// point moves by at most 0.005° against exact trigonometry.
//
// The hot path works a block (32 units) at a time, in separate loops: read the units and flag
// the points (a block without any stops there), the 32 table indices and entries (reused by the
// other block of a dual-return pair), the formulas over arrays (vector instructions; the same
// operations in the same order as one point at a time, so the same bits), then the store of
// the kept points. The per-laser terms are kept per bank as arrays (BankGeometry) for this.
#include "sim/velodyne/frame_assembler.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

namespace sim::velodyne {
namespace {

// The in-place store writes a point's time offset, ring, return index and reserved byte as one
// little-endian word, and its x, y, z, intensity as one Xyzi.
static_assert(std::endian::native == std::endian::little, "LidarPoint tail written as a little-endian word");
static_assert(offsetof(LidarPoint, ring) == 20 && offsetof(LidarPoint, return_index) == 22 &&
              offsetof(LidarPoint, reserved) == 23 && sizeof(LidarPoint) == 24);
// A unit is read as a 4-byte word: the last unit of the last block reads one byte past its
// block, which must still be inside the (exactly packet_size) packet.
static_assert(blocks_per_packet * block_size + 1 <= packet_size);

constexpr std::int64_t hour_ns = 3'600'000'000'000;
constexpr std::int32_t full_turn = 36000;  // 0.01°
constexpr double pi = 3.14159265358979323846;
// A step between sequences above this (1°) is a gap in the data, not the motor's motion.
constexpr float max_plausible_step = 100.0f;

std::int64_t floor_div(std::int64_t a, std::int64_t b) noexcept {
  const std::int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

// Fraction of the step between sequences (VLP-16: between blocks, two sequences) at which the
// unit of bank `bank` fires, from the manuals' firing tables.
float unit_fraction(Model model, unsigned bank, unsigned unit) noexcept {
  switch (model) {
    case Model::vlp16:
    case Model::puck_hires: {
      const auto laser = static_cast<float>(unit % 16);
      const auto firing = static_cast<float>(unit / 16);
      return (laser * 2.304f + firing * 55.296f) / 110.592f;
    }
    case Model::vlp32c: return (static_cast<float>(unit / 2) * 2.304f) / 55.296f;
    case Model::hdl32e: return (static_cast<float>(unit) * 1.152f) / 46.08f;
    case Model::vls128: {
      const unsigned group = (bank * 32 + unit) / 8;
      return (2.665f / 53.3f) * static_cast<float>(group + group / 8);
    }
    case Model::hdl64e: return 0.0f;
  }
  return 0.0f;
}

// nebula decodes the VLP-32C, HDL-32E and HDL-64E with one decoder (its VLP-32 decoder), which
// moves unit j of a block by j · 2.304/55.296 of the difference to the next block: each laser
// one slot after the previous, where the VLP-32C fires its lasers in pairs (the manual's table,
// unit_fraction) and the HDL-32E's and HDL-64E's have other slots. nebula's reference clouds
// carry it: on its VLP-32C capture the two differ by up to 0.15° at unit 31.
bool nebula_per_unit_slots(Model model) noexcept {
  return model == Model::vlp32c || model == Model::hdl32e || model == Model::hdl64e;
}

std::uint32_t clamp_offset(std::int64_t ns) noexcept {
  if (ns < 0) return 0;
  if (ns > std::numeric_limits<std::uint32_t>::max()) return std::numeric_limits<std::uint32_t>::max();
  return static_cast<std::uint32_t>(ns);
}

}  // namespace

std::int64_t packet_time_ns(std::uint32_t timestamp_us, std::int64_t reference_ns) noexcept {
  const std::int64_t top = floor_div(reference_ns, hour_ns) * hour_ns;
  std::int64_t t = top + std::int64_t{timestamp_us} * 1000;
  if (t - reference_ns > hour_ns / 2) t -= hour_ns;
  if (reference_ns - t > hour_ns / 2) t += hour_ns;
  return t;
}

// cos and sin of 0.00°…359.99°, computed once for every assembler of the process.
const FrameAssembler::CosSin* FrameAssembler::shared_trig_table() {
  static const std::vector<CosSin> table = [] {
    std::vector<CosSin> t(full_turn);
    for (std::int32_t a = 0; a < full_turn; ++a) {
      const auto radians = static_cast<float>(0.01 * a * pi / 180.0);
      t[static_cast<std::size_t>(a)] = {std::cos(radians), std::sin(radians)};
    }
    return t;
  }();
  return table.data();
}

Expected<FrameAssembler> FrameAssembler::create(Calibration calibration, AssemblerOptions options) {
  const ModelInfo& i = info(options.model);
  if (calibration.lasers() != i.lasers) {
    return Error{ErrorCode::invalid_argument,
                 "the calibration has " + std::to_string(calibration.lasers()) + " lasers but a " +
                     std::string(to_string(options.model)) + " has " + std::to_string(i.lasers) +
                     "; give the file of this sensor (--calibration)."};
  }
  const float min = options.min_range_m.value_or(i.min_range_m);
  const float max = options.max_range_m.value_or(i.max_range_m);
  if (!(min >= 0) || !(max > min)) {
    return Error{ErrorCode::invalid_argument,
                 "the range limits are inverted or negative; --min-range must be below --max-range."};
  }
  if (!(options.cut_azimuth_deg >= 0 && options.cut_azimuth_deg < 360)) {
    return Error{ErrorCode::invalid_argument, "the cut azimuth must be in [0, 360) degrees."};
  }
  return FrameAssembler(std::move(calibration), std::move(options));
}

FrameAssembler::FrameAssembler(Calibration calibration, AssemblerOptions options)
    : calibration_(std::move(calibration)), options_(std::move(options)), info_(&info(options_.model)) {
  min_range_m_ = options_.min_range_m.value_or(info_->min_range_m);
  max_range_m_ = options_.max_range_m.value_or(info_->max_range_m);
  cut_centi_ = static_cast<std::uint16_t>(std::lround(options_.cut_azimuth_deg * 100) % full_turn);
  if (options_.azimuth_window) {
    windowed_ = true;
    window_points_ = !options_.azimuth_window->block_azimuth_only;
    window_min_centi_ = static_cast<std::int32_t>(std::lround(options_.azimuth_window->min_deg * 100));
    window_max_centi_ = static_cast<std::int32_t>(std::lround(options_.azimuth_window->max_deg * 100));
  }
  trig_table_ = shared_trig_table();
  min_point_delta_centi_ = 0;
  max_point_delta_centi_ = 0;
  double largest_rot_centi = 0;
  for (std::size_t l = 0; l < calibration_.lasers(); ++l) {
    const double rot_centi = calibration_[l].rot_correction * 180.0 / pi * 100.0;
    min_point_delta_centi_ = std::min(min_point_delta_centi_, -rot_centi);
    max_point_delta_centi_ = std::max(max_point_delta_centi_, -rot_centi);
    largest_rot_centi = std::max(largest_rot_centi, std::abs(rot_centi));
  }
  // Rounding, and the interpolation (at most two steps of a plausible size) on top.
  min_point_delta_centi_ -= 1;
  max_point_delta_centi_ += 1 + 2 * max_plausible_step;
  build_unit_geometry();
  // In place needs every point's offset from its sequence azimuth within half a turn (no wrap
  // ambiguity): rot_corrections of real sensors are a few degrees.
  in_place_ = options_.interpolation == AzimuthInterpolation::firing_time &&
              options_.cut_by == CutBy::point_azimuth && !windowed_ && largest_rot_centi < 17000;
  // Points of the next revolution decoded before the current one completes: those within the
  // laser offsets' spread of the cut (VLS-128: about 12°, 20 packets) plus two packets.
  const double spread_centi = max_point_delta_centi_ - min_point_delta_centi_;
  const double packets_in_spread = spread_centi / 10.0 + 2;  // ≥ 0.1° per packet at any rpm
  out_.reserve_carry(static_cast<std::size_t>(packets_in_spread) * info_->max_points_per_packet());
}

void FrameAssembler::build_unit_geometry() noexcept {
  const bool two_sequences = info_->sequences_per_block == 2;
  const bool nebula_slots =
      options_.interpolation == AzimuthInterpolation::nebula && nebula_per_unit_slots(options_.model);
  for (unsigned bank = 0; bank < banks; ++bank) {
    BankGeometry& g = banks_[bank];
    g.cos_vert.fill(1.0f);
    g.max_intensity.fill(255.0);
    for (unsigned u = 0; u < units_per_block; ++u) {
      // nebula's per-unit slots: the unit's index here, the slot's share of the step in
      // nebula_block_azimuths, so step · fraction is nebula's float expression to the bit.
      g.fraction[u] = nebula_slots ? static_cast<float>(u) : unit_fraction(options_.model, bank, u);
      // VLP-16 and Puck: two sequences of 16 lasers per block; the rest one laser per unit.
      const unsigned laser = two_sequences ? u % 16 : bank * 32 + u;
      if (laser >= calibration_.lasers()) continue;  // a bank this model does not send
      const LaserCorrection& c = calibration_[laser];
      g.rot_centi[u] = c.rot_correction * 180.0 / pi * 100.0;
      g.cos_vert[u] = static_cast<float>(std::cos(c.vert_correction));
      g.sin_vert[u] = static_cast<float>(std::sin(c.vert_correction));
      g.dist_correction[u] = static_cast<float>(c.dist_correction);
      g.time_ns[u] = laser_firing_ns(options_.model, laser) + (two_sequences ? (u / 16) * info_->sequence_ns : 0);
      g.ring[u] = calibration_.ring(laser);
      g.tail[u] = g.time_ns[u] | (std::uint64_t{g.ring[u]} << 32);
      max_unit_time_ns_ = std::max(max_unit_time_ns_, g.time_ns[u]);
      if (c.needs_full_model()) {
        full_model_ = true;
        g.vert_offset[u] = static_cast<float>(c.vert_offset_correction);
        g.horiz_offset[u] = static_cast<float>(c.horiz_offset_correction);
        if (c.two_point()) {
          g.two_point_dc[u] = static_cast<float>(c.dist_correction);
          g.two_point_dx[u] = static_cast<float>(c.dist_correction_x);
          g.two_point_dy[u] = static_cast<float>(c.dist_correction_y);
        }
      }
      if (c.corrects_intensity()) {
        intensity_model_ = true;
        const double focal = 1.0 - c.focal_distance / 13100.0;
        g.focal_term[u] = 256.0 * focal * focal;
        g.focal_slope[u] = c.focal_slope;
        g.min_intensity[u] = c.min_intensity;
        g.max_intensity[u] = c.max_intensity;
      }
    }
  }
}

void FrameAssembler::set_output(std::span<LidarPoint> output) noexcept {
  // Replaced in the middle of a frame, its points so far stay in the old span (lost to it) and
  // the carry-over keeps the next frame's (this used to copy them into the new span, into the
  // wrong revolution: sim/lidar/frame_output.hpp); else the carry-over moves to its front.
  const lidar::FrameOutput::Attached attached = out_.attach(output);
  if (attached.lost > 0) current_.whole = false;
  drop_points(current_, attached.lost + attached.did_not_fit);
}

void FrameAssembler::drop_points(FrameState& frame, std::size_t points) noexcept {
  frame.dropped += static_cast<std::uint32_t>(points);
  counters_.dropped_points += points;
}

bool FrameAssembler::starts_whole(std::int64_t revolution) const noexcept {
  if (options_.cut_by == CutBy::packet) return next_is_whole_;
  // Whole when no point of it can have come before the first block decoded since the start.
  return static_cast<double>(revolution * full_turn) > static_cast<double>(first_position_) + max_point_delta_centi_;
}

void FrameAssembler::start(FrameState& frame, std::int64_t point_ns, std::int64_t host_ns, bool whole) noexcept {
  frame = FrameState{};
  frame.started = true;
  frame.whole = whole;
  frame.stamp_ns = point_ns;
  frame.host_ns = host_ns;
}

void FrameAssembler::emit(const LidarPoint& point, std::int64_t position, std::int64_t point_ns,
                          std::int64_t host_ns) noexcept {
  // The revolution without a division in the common case: this one or the next.
  const std::int64_t relative = position - current_revolution_ * full_turn;
  const std::int64_t revolution = !current_.started               ? floor_div(position, full_turn)
                                  : (relative >= 0 && relative < full_turn) ? current_revolution_
                                  : (relative >= full_turn && relative < 2 * full_turn)
                                      ? current_revolution_ + 1
                                      : floor_div(position, full_turn);
  if (!current_.started) {
    current_revolution_ = revolution;
    start(current_, point_ns, host_ns, starts_whole(revolution));
  } else if (revolution > current_revolution_ + 1 ||
             (revolution == current_revolution_ + 1 && !out_.attached())) {
    // Half a revolution or more went missing (or no span to keep two frames apart): the frame
    // in progress can never be whole; drop it and start over at this point.
    abandon_current();
    current_revolution_ = revolution;
    start(current_, point_ns, host_ns, false);
  }
  FrameState* frame = &current_;
  LidarPoint* slot = nullptr;
  if (revolution == current_revolution_) {
    slot = out_.take_current();
  } else if (revolution == current_revolution_ + 1) {
    if (!next_.started) start(next_, point_ns, host_ns, starts_whole(revolution));
    frame = &next_;
    slot = out_.take_carry();  // a span is attached (else the frame in progress was abandoned)
  }  // else: a point of a revolution already published (it came too late)
  if (slot == nullptr) {
    ++frame->dropped;
    ++counters_.dropped_points;
    return;
  }
  *slot = point;
  slot->time_offset_ns = clamp_offset(point_ns - frame->stamp_ns);
}

void FrameAssembler::abandon_current() noexcept {
  if (current_.started) ++counters_.partial_frames_dropped;
  current_ = FrameState{};
  next_ = FrameState{};
  out_.clear();
  next_is_whole_ = false;
}

void FrameAssembler::complete(PushResult& result) noexcept {
  ++current_revolution_;
  const bool publish = current_.whole || options_.emit_partial_frames;
  if (publish && out_.attached()) {
    CompletedFrame frame;
    frame.point_count = out_.output_count();
    frame.stamp_ns = current_.stamp_ns;
    frame.host_receive_ns = current_.host_ns;
    frame.index = frame_index_++;
    frame.packets = current_.packets;
    frame.lost_packets = current_.lost;
    frame.dropped_points = current_.dropped;
    frame.whole = current_.whole;
    result.frame = frame;
    ++counters_.frames;
    out_.hand_out();  // the span is the caller's until set_output; next_ is in the carry-over
    current_ = next_;
  } else {
    if (current_.started) ++counters_.partial_frames_dropped;
    // Reuse the span: the next frame's points move to its front. Without a span the carry-over
    // held the frame in progress: its points are gone with it.
    const bool had_span = out_.attached();
    const lidar::FrameOutput::Advanced advanced = out_.advance();
    if (!had_span) counters_.dropped_points += advanced.discarded;
    current_ = next_;
    drop_points(current_, advanced.did_not_fit);
  }
  next_ = FrameState{};
  next_is_whole_ = true;
}

void FrameAssembler::move_packet_tail_to_next() noexcept {
  // nebula's rule (reference note §1): from the end, the points within 90° after the cut. (A
  // 2° limit left 95 points of the VLP-16 capture's wrap packet, 0.08°–2.28°, in the frame
  // before nebula's.)
  std::size_t keep = packet_points_;
  while (keep > 0 && packet_point_phase_[keep - 1] < 9000) --keep;
  const std::span<LidarPoint> moved = out_.move_tail_to_carry(packet_points_ - keep);
  if (moved.empty()) return;
  const std::int64_t first_ns = current_.stamp_ns + moved.front().time_offset_ns;
  start(next_, first_ns, current_.host_ns, true);
  for (LidarPoint& p : moved) p.time_offset_ns = clamp_offset(current_.stamp_ns + p.time_offset_ns - first_ns);
}

void FrameAssembler::count_packet(std::int64_t packet_ns, const Packet& packet) noexcept {
  // The sequences this packet holds, as the decoder reads it: a VLS-128 dual packet's 8 blocks are
  // one sequence (pairs per bank), not the 1.5 that half of a single packet's 3 would say.
  const unsigned slot = info_->blocks_per_sequence * (packet.dual() ? 2U : 1U);
  const unsigned sequences = packet.blocks() * unsigned{info_->sequences_per_block} / slot;
  const std::int64_t period = std::int64_t{info_->sequence_ns} * sequences;
  if (have_packet_ && period > 0) {
    const std::int64_t gap = packet_ns - last_packet_ns_;
    if (gap > period * 3 / 2 && gap < 1'000'000'000) {
      const auto lost = static_cast<std::uint32_t>((gap + period / 2) / period - 1);
      counters_.lost_packets += lost;
      if (current_.started) current_.lost += lost;
    }
  }
  last_packet_ns_ = packet_ns;
}

void FrameAssembler::block_azimuths(const Packet& packet, std::array<BlockAzimuth, blocks_per_packet>& out) noexcept {
  const unsigned blocks = packet.blocks();
  const unsigned per_slot = info_->blocks_per_sequence * (packet.dual() ? 2U : 1U);
  // The sensor's step between sequences, learned across packets for the packet's last slot
  // (and the VLS-128's dual-return packets, which hold one sequence).
  if (have_packet_) {
    const auto across = static_cast<float>((full_turn + packet.azimuth(0) - last_packet_azimuth_) % full_turn);
    const unsigned slots = blocks / per_slot;
    const float step = slots > 0 ? across / static_cast<float>(slots) : 0.0f;
    if (step <= max_plausible_step && blocks == per_slot) last_step_ = step;
  }
  for (unsigned first = 0; first < blocks; first += per_slot) {
    const std::uint16_t az = packet.azimuth(first);
    float step = last_step_;
    if (first + per_slot < blocks) {
      const auto next = static_cast<float>((full_turn + packet.azimuth(first + per_slot) - az) % full_turn);
      if (next <= max_plausible_step) step = last_step_ = next;
    }
    // VLP-16: a block holds two sequences; the fractions are of the block's step.
    for (unsigned b = first; b < first + per_slot && b < blocks; ++b) out[b] = {az, step};
  }
}

void FrameAssembler::nebula_block_azimuths(const Packet& packet,
                                           std::array<BlockAzimuth, blocks_per_packet>& out) const noexcept {
  // nebula walks the blocks with the azimuth of "the next block" (the next pair in dual
  // return), carrying it forward; the differences it takes follow from that walk.
  const unsigned dual = packet.dual() ? 1 : 0;
  const unsigned stride = 1 + dual;
  // The block that gets no interpolation: the packet's last (VLS-128), the last block
  // (VLP-16; dual: the last pair's first), or, in nebula's VLP-32 decoder, the last block in
  // single return and block 7 in dual, which the walk never reaches (10 and 11 keep the last
  // difference).
  const bool slots = nebula_per_unit_slots(options_.model);
  const unsigned zero_block = options_.model == Model::vls128 ? packet.blocks() - 1
                              : slots                         ? blocks_per_packet - 4 * dual - 1
                                                              : blocks_per_packet - dual - 1;
  float last_diff = 0;
  std::uint16_t next = 0;
  for (unsigned b = 0; b < packet.blocks(); ++b) {
    const std::uint16_t az = b == 0 ? packet.azimuth(0) : next;
    float diff;
    if (b < blocks_per_packet - stride) {
      next = packet.azimuth(b + stride);
      diff = static_cast<float>((full_turn + next - az) % full_turn);
      last_diff = diff;
    } else {
      diff = b == zero_block ? 0.0f : last_diff;
    }
    // Per-unit slots: the step is one slot's share (nebula's `diff · 2.304 / 55.296`, in
    // float), and the unit's fraction its index (build_unit_geometry). A jump of more than 1°
    // between blocks is no rotation (a damaged packet): 31 slots of it could pass a whole
    // turn, so such a block is not interpolated.
    if (slots) out[b] = {az, diff <= max_plausible_step ? diff * 2.304f / 55.296f : 0.0f};
    else out[b] = {az, diff};
  }
}

PushResult FrameAssembler::push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns,
                                std::int64_t time_reference_ns) noexcept {
  PushResult result;
  Packet packet;
  result.error = Packet::parse(payload, options_.model, packet);
  if (result.error != PacketError::none) {
    ++counters_.rejected[static_cast<std::size_t>(result.error)];
    if (result.error == PacketError::wrong_model) {
      ++counters_.wrong_model;
    } else {
      ++counters_.malformed;
    }
    return result;
  }
  ++counters_.packets;
  last_mode_ = packet.return_mode();
  const std::int64_t packet_ns =
      packet_time_ns(packet.timestamp_us(), time_reference_ns != 0 ? time_reference_ns : host_receive_ns);
  count_packet(packet_ns, packet);
  result.packet_ns = packet_ns;

  std::array<BlockAzimuth, blocks_per_packet> azimuths{};
  block_azimuths(packet, azimuths);  // also learns the step across packets
  if (options_.interpolation == AzimuthInterpolation::nebula) nebula_block_azimuths(packet, azimuths);

  const unsigned per_slot = info_->blocks_per_sequence * (packet.dual() ? 2U : 1U);
  const bool by_packet = options_.cut_by == CutBy::packet;
  const auto phase_of = [&](std::uint16_t az) {
    return static_cast<std::uint16_t>((full_turn + az - cut_centi_) % full_turn);
  };
  packet_first_point_ = out_.output_count();
  packet_points_ = 0;
  bool wrapped = false;
  std::int64_t slot_position = 0;
  for (unsigned b = 0; b < packet.blocks(); ++b) {
    if (b % per_slot == 0) {
      const std::uint16_t phase = phase_of(packet.azimuth(b));
      if (have_block_ && phase + full_turn / 2 < last_phase_) {
        ++block_revolution_;
        wrapped = true;
      }
      last_phase_ = phase;
      slot_position = block_revolution_ * full_turn + phase;
      if (!have_block_) first_position_ = slot_position;
      have_block_ = true;
    }
    decode_block(packet, b, azimuths[b], by_packet ? current_revolution_ * full_turn : slot_position,
                 packet_ns, host_receive_ns);
  }
  if (current_.started) ++current_.packets;
  if (next_.started) ++next_.packets;
  last_block_position_ = slot_position;
  last_packet_azimuth_ = packet.azimuth(0);
  have_packet_ = true;

  if (by_packet) {
    // nebula: the scan ends with the packet whose blocks wrap, or that starts below the
    // previous packet's start.
    const std::uint16_t first_phase = phase_of(packet.azimuth(0));
    ++packets_since_cut_;
    const bool ends = packets_since_cut_ > 1 && (wrapped || first_phase < last_packet_phase_);
    last_packet_phase_ = first_phase;
    if (ends) packets_since_cut_ = 0;
    if (ends && current_.started) {
      // nebula's VLP-32 decoder keeps the whole wrap packet in the scan: its 90° test compares
      // 2π + azimuth − phase without wrapping it, which no point passes for a phase up to 270°.
      if (!nebula_per_unit_slots(options_.model)) move_packet_tail_to_next();
      complete(result);
    }
    return result;
  }
  const double boundary = static_cast<double>((current_revolution_ + 1) * full_turn);
  if (current_.started && static_cast<double>(slot_position) + min_point_delta_centi_ >= boundary) {
    complete(result);
  }
  return result;
}

bool FrameAssembler::in_window(std::int32_t azimuth_centi) const noexcept {
  return window_min_centi_ <= window_max_centi_
             ? (azimuth_centi >= window_min_centi_ && azimuth_centi <= window_max_centi_)
             : (azimuth_centi >= window_min_centi_ || azimuth_centi <= window_max_centi_);
}

void FrameAssembler::decode_block(const Packet& packet, unsigned block, const BlockAzimuth& azimuth,
                                  std::int64_t block_position, std::int64_t packet_ns,
                                  std::int64_t host_ns) noexcept {
  // One instance of the point loop per calibration kind, so no point asks which model it needs.
  if (full_model_) {
    if (intensity_model_) {
      decode_block_as<true, true>(packet, block, azimuth, block_position, packet_ns, host_ns);
    } else {
      decode_block_as<true, false>(packet, block, azimuth, block_position, packet_ns, host_ns);
    }
  } else if (intensity_model_) {
    decode_block_as<false, true>(packet, block, azimuth, block_position, packet_ns, host_ns);
  } else {
    decode_block_as<false, false>(packet, block, azimuth, block_position, packet_ns, host_ns);
  }
}

template <bool Full, bool Intensity>
void FrameAssembler::decode_block_as(const Packet& packet, unsigned block, const BlockAzimuth& azimuth,
                                     std::int64_t block_position, std::int64_t packet_ns,
                                     std::int64_t host_ns) noexcept {
  BlockContext context;
  if (!block_context(packet, block, azimuth, packet_ns, context)) return;
  if (fits_in_place(context, block_position)) {
    decode_in_place<Full, Intensity>(context);
  } else {
    decode_point_by_point<Full, Intensity>(context, block_position, host_ns);
  }
}

bool FrameAssembler::block_context(const Packet& packet, unsigned block, const BlockAzimuth& azimuth,
                                   std::int64_t packet_ns, BlockContext& out) const noexcept {
  const bool dual = packet.dual();
  const unsigned return_index = dual ? packet.return_index(block) : 0;
  if (dual && options_.returns == ReturnFilter::last && return_index != 0) return false;
  if (dual && options_.returns == ReturnFilter::strongest && return_index == 0) return false;
  if (windowed_ && options_.azimuth_window->block_azimuth_too && !in_window(azimuth.base)) return false;
  if (windowed_ && !window_points_ && !in_window(packet.azimuth(block))) return false;
  // Both returns: the second is dropped where it repeats the first (the firing's only return).
  const bool compare = return_index == 1 && options_.returns == ReturnFilter::both && options_.drop_identical_returns;
  const unsigned bank = packet.laser(block, 0) / 32 % banks;
  const unsigned per_slot = info_->blocks_per_sequence * (dual ? 2U : 1U);
  out.units = packet.units(block);
  out.partner = compare ? packet.units(packet.partner(block)) : nullptr;
  out.geometry = &banks_[bank];
  out.bank = bank;
  out.trig = trig_table_;
  out.base = static_cast<float>(azimuth.base);
  out.step = azimuth.step;
  out.unit_m = info_->distance_unit_m;
  out.min_range_m = min_range_m_;
  out.max_range_m = max_range_m_;
  out.real_azimuth = packet.azimuth(block - block % per_slot);
  out.ns = packet_ns + std::int64_t{packet.sequence(block, 0)} * info_->sequence_ns;
  out.return_index = static_cast<std::uint8_t>(return_index);
  out.time_base = 0;  // fits_in_place sets it for the in-place path
  return true;
}

bool FrameAssembler::fits_in_place(BlockContext& block, std::int64_t block_position) const noexcept {
  if (!in_place_ || !current_.started || out_.output_room() < units_per_block) {  // no span: no room
    return false;
  }
  // Every point's position lies within the deltas of its sequence's: all in this revolution?
  const auto first = static_cast<double>(current_revolution_ * full_turn);
  const auto position = static_cast<double>(block_position);
  if (position + min_point_delta_centi_ < first || position + max_point_delta_centi_ >= first + full_turn) {
    return false;
  }
  // And every point's time offset fits without clamping.
  block.time_base = block.ns - current_.stamp_ns;
  return block.time_base >= 0 &&
         block.time_base <= std::int64_t{std::numeric_limits<std::uint32_t>::max()} - max_unit_time_ns_;
}

// The table index (azimuth in 0.01°, 0…35,999) of each unit of the block: the interpolated
// azimuth minus the laser's rot_correction, rounded as nebula and ros-drivers do (see the top
// of this file). No branch: the compiler computes the 32 with vector instructions.
void FrameAssembler::azimuth_indices(const BlockContext& block, PerUnit<std::int32_t>& out) noexcept {
  const BankGeometry& g = *block.geometry;
  for (unsigned u = 0; u < units_per_block; ++u) {
    const float interpolated = block.base + block.step * g.fraction[u];
    float corrected = static_cast<float>(static_cast<double>(interpolated) - g.rot_centi[u]);
    corrected += corrected < 0.0f ? static_cast<float>(full_turn) : 0.0f;
    const auto rounded = static_cast<std::int32_t>(corrected + 0.5f);
    out[u] = rounded >= full_turn ? rounded - full_turn : rounded;
  }
}

// Reads the block's 32 units and flags the points: a return, within the range limits, and not
// the repeat of its pair's other return. False when none is (sky, or a dual-return block that
// repeats its pair): the block then needs no trigonometry at all.
bool FrameAssembler::flag_points(const BlockContext& block, PerUnit<std::int32_t>& raw, PerUnit<float>& distance,
                                 PerUnit<float>& intensity, PerUnit<std::uint32_t>& keep) noexcept {
  const BankGeometry& g = *block.geometry;
  const float unit_m = block.unit_m;
  const float min_range_m = block.min_range_m;
  const float max_range_m = block.max_range_m;
  // Each unit's 3 bytes (distance, reflectivity) read as one little-endian 4-byte word; the
  // last unit's word ends on the next block's first byte or the timestamp, inside the packet.
  // (The scalar load loops are unrolled: a load and a store a unit, no loop counter.)
  PerUnit<std::uint32_t> word;
#pragma GCC unroll 32
  for (unsigned u = 0; u < units_per_block; ++u) std::memcpy(&word[u], block.units + u * 3, sizeof(std::uint32_t));
  for (unsigned u = 0; u < units_per_block; ++u) {
    const auto r = static_cast<std::int32_t>(word[u] & 0xFFFF);
    const float d = static_cast<float>(r) * unit_m + g.dist_correction[u];
    raw[u] = r;
    distance[u] = d;
    keep[u] = (r != 0) & (d > min_range_m) & (d < max_range_m);
    intensity[u] = static_cast<float>((word[u] >> 16) & 0xFF);
  }
  if (block.partner != nullptr) {
#pragma GCC unroll 32
    for (unsigned u = 0; u < units_per_block; ++u) std::memcpy(&word[u], block.partner + u * 3, sizeof(std::uint32_t));
    for (unsigned u = 0; u < units_per_block; ++u) keep[u] &= raw[u] != static_cast<std::int32_t>(word[u] & 0xFFFF);
  }
  std::uint32_t any = 0;
  for (unsigned u = 0; u < units_per_block; ++u) any |= keep[u];
  return any != 0;
}

// Decodes the block's 32 units into `out` (every field but the time); false when none is a
// point. The loads (packet bytes, sin/cos table) are loops of their own; the arithmetic reads
// only arrays and is one loop per formula, so the compiler computes four units per vector
// instruction and every point gets exactly the operations of the scalar formula (same results
// to the bit).
template <bool Full, bool Intensity>
bool FrameAssembler::decode_units(const BlockContext& block, BlockTrig& trig, BlockPoints& out) noexcept {
  PerUnit<std::int32_t> raw;
  PerUnit<float> distance;
  PerUnit<float> intensity;
  if (!flag_points(block, raw, distance, intensity, out.keep)) return false;
  if (trig.bank != block.bank || trig.base != block.base || trig.step != block.step) {
    azimuth_indices(block, trig.azimuth);
#pragma GCC unroll 32
    for (unsigned u = 0; u < units_per_block; ++u) trig.trig[u] = block.trig[trig.azimuth[u]];
    trig.bank = block.bank;
    trig.base = block.base;
    trig.step = block.step;
  }
  const BankGeometry& g = *block.geometry;
  if constexpr (Intensity) {
    // The HDL-64E's focal intensity model (ros-drivers/velodyne rawdata.cc), in double as there.
    for (unsigned u = 0; u < units_per_block; ++u) {
      const double scaled = 1.0 - static_cast<double>(raw[u]) * (1.0 / 65535.0);
      const double value = intensity[u] + g.focal_slope[u] * std::abs(g.focal_term[u] - 256.0 * scaled * scaled);
      intensity[u] = static_cast<float>(std::clamp(value, g.min_intensity[u], g.max_intensity[u]));
    }
  }
  if constexpr (Full) {
    full_model_points(g, distance, intensity, trig.trig, out);
  } else {
    for (unsigned u = 0; u < units_per_block; ++u) {
      const float xy = distance[u] * g.cos_vert[u];
      out.xyzi[u] = {xy * trig.trig[u].cos, -(xy * trig.trig[u].sin), distance[u] * g.sin_vert[u], intensity[u]};
    }
  }
  return true;
}

// The HDL-64E model (ros-drivers/velodyne rawdata.cc): optical-centre offsets and the
// two-point distance correction, in the sensor's frame (x right, y forward), then ROS.
void FrameAssembler::full_model_points(const BankGeometry& g, const PerUnit<float>& distance,
                                       const PerUnit<float>& intensity, const PerUnit<CosSin>& trig,
                                       BlockPoints& out) noexcept {
  for (unsigned u = 0; u < units_per_block; ++u) {
    const float d = distance[u];
    const float cos_a = trig[u].cos;
    const float sin_a = trig[u].sin;
    const float vo = g.vert_offset[u];
    const float ho = g.horiz_offset[u];
    const float cos_vert = g.cos_vert[u];
    const float sin_vert = g.sin_vert[u];
    float xy = d * cos_vert - vo * sin_vert;
    const float xx = std::abs(xy * sin_a - ho * cos_a);
    const float yy = std::abs(xy * cos_a + ho * sin_a);
    // Linear between the two calibration distances (2.4 m / 1.93 m and 25.04 m); a product with
    // the constant reciprocal instead of a division per point.
    const float dc = g.two_point_dc[u];
    const float corr_x = (dc - g.two_point_dx[u]) * (xx - 2.4f) * (1.0f / (25.04f - 2.4f)) + g.two_point_dx[u] - dc;
    const float corr_y = (dc - g.two_point_dy[u]) * (yy - 1.93f) * (1.0f / (25.04f - 1.93f)) + g.two_point_dy[u] - dc;
    xy = (d + corr_x) * cos_vert - vo * sin_vert;
    const float vx = xy * sin_a - ho * cos_a;
    xy = (d + corr_y) * cos_vert - vo * sin_vert;
    const float vy = xy * cos_a + ho * sin_a;
    out.xyzi[u] = {vy, -vx, (d + corr_y) * sin_vert + vo * cos_vert, intensity[u]};
  }
}

// Every point of the block goes to the output; a slot is written for every unit and kept only
// for a point, so the loop has no branch that depends on the data. A point is two copies: its
// x, y, z, intensity (16 bytes) and its last 8 bytes, the bank's time, ring word plus this
// block's time base and return index (no carry: fits_in_place keeps the time below 2^32).
template <bool Full, bool Intensity>
void FrameAssembler::decode_in_place(const BlockContext& block) noexcept {
  BlockPoints points;
  if (!decode_units<Full, Intensity>(block, block_trig_, points)) return;
  const PerUnit<std::uint64_t>& tail = block.geometry->tail;
  const std::uint64_t block_tail = static_cast<std::uint64_t>(block.time_base) | (std::uint64_t{block.return_index} << 48);
  // How far the write position moves after each unit: a point's size, or 0 for a unit dropped.
  PerUnit<std::uint32_t> advance;
  for (unsigned u = 0; u < units_per_block; ++u) advance[u] = points.keep[u] * std::uint32_t{sizeof(LidarPoint)};
  auto* const first = reinterpret_cast<unsigned char*>(out_.output_end());
  unsigned char* point = first;
#pragma GCC unroll 32
  for (unsigned u = 0; u < units_per_block; ++u) {
    const std::uint64_t last_bytes = tail[u] + block_tail;
    std::memcpy(point, &points.xyzi[u], sizeof(Xyzi));
    std::memcpy(point + offsetof(LidarPoint, time_offset_ns), &last_bytes, sizeof last_bytes);
    point += advance[u];
  }
  out_.extend(static_cast<std::size_t>(point - first) / sizeof(LidarPoint));
}

// Near a cut, in the nebula modes, or with an azimuth window: each point finds its frame.
template <bool Full, bool Intensity>
void FrameAssembler::decode_point_by_point(const BlockContext& block, std::int64_t block_position,
                                           std::int64_t host_ns) noexcept {
  const bool by_packet = options_.cut_by == CutBy::packet;
  BlockPoints points;
  if (!decode_units<Full, Intensity>(block, block_trig_, points)) return;
  const BankGeometry& g = *block.geometry;
  for (unsigned u = 0; u < units_per_block; ++u) {
    const std::int32_t azimuth = block_trig_.azimuth[u];
    if (points.keep[u] == 0) continue;
    if (window_points_ && !in_window(azimuth)) continue;
    // Where the point lies on the unwrapped azimuth axis (0.01° since the first revolution).
    std::int64_t position;
    if (by_packet) {
      position = (current_.started ? current_revolution_ : 0) * full_turn;
    } else {
      std::int32_t offset = azimuth - block.real_azimuth;  // within a few degrees, or across 0°
      if (offset >= full_turn / 2) offset -= full_turn;
      if (offset < -full_turn / 2) offset += full_turn;
      position = block_position + offset;
    }
    const Xyzi& v = points.xyzi[u];
    const LidarPoint p{v.x, v.y, v.z, v.intensity, 0, g.ring[u], block.return_index, 0};
    const std::size_t before = out_.output_count();
    emit(p, position, block.ns + g.time_ns[u], host_ns);
    if (by_packet && out_.attached() && out_.output_count() == before + 1 &&
        packet_points_ < packet_point_phase_.size()) {
      packet_point_phase_[packet_points_++] =
          static_cast<std::uint16_t>((full_turn + azimuth - cut_centi_) % full_turn);
    }
  }
}

std::optional<CompletedFrame> FrameAssembler::finish() noexcept {
  if (!current_.started || !out_.attached()) {
    reset();
    return std::nullopt;
  }
  CompletedFrame frame;
  frame.point_count = out_.output_count();
  frame.stamp_ns = current_.stamp_ns;
  frame.host_receive_ns = current_.host_ns;
  frame.index = frame_index_++;
  frame.packets = current_.packets;
  frame.lost_packets = current_.lost;
  frame.dropped_points = current_.dropped;
  frame.whole = false;
  ++counters_.frames;
  // The next frame's few points cannot be kept apart from the finished one.
  counters_.dropped_points += out_.drop_next();
  out_.hand_out();
  current_ = FrameState{};
  next_ = FrameState{};
  have_block_ = false;
  have_packet_ = false;
  next_is_whole_ = false;
  return frame;
}

void FrameAssembler::reset() noexcept {
  current_ = FrameState{};
  next_ = FrameState{};
  out_.clear();
  next_is_whole_ = false;
  have_block_ = false;
  have_packet_ = false;
  block_revolution_ = 0;
  current_revolution_ = 0;
}

}  // namespace sim::velodyne
