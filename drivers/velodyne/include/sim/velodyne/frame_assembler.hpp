// SPDX-License-Identifier: Apache-2.0
// FrameAssembler: Velodyne data packets -> one frame per revolution, decoded straight into a
// span the caller owns (a SIM writer's loaned slot). The live driver and the pcap replay use
// this same object, as the Hesai family does (sim/hesai/frame_assembler.hpp):
//
//   auto assembler = FrameAssembler::create(calibration, options).value();
//   assembler.set_output(loan.as<sim::LidarPoint>());
//   PushResult r = assembler.push(payload, host_receive_ns);
//   if (r.frame) { commit r.frame->point_count points; set_output(next loan); }
//
// A point belongs to the revolution its own azimuth falls in (block azimuth + firing-time
// interpolation − the laser's rot_correction, rounded to 0.01°): a frame holds exactly the
// points with azimuth in [cut, cut + 360°). Near the cut, points of the next revolution wait
// in a carry-over buffer sized at create(); nothing is allocated after create().
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/lidar/assembler_counters.hpp"
#include "sim/lidar/completed_frame.hpp"
#include "sim/lidar/frame_output.hpp"
#include "sim/lidar_point.hpp"
#include "sim/result.hpp"
#include "sim/velodyne/calibration.hpp"
#include "sim/velodyne/model.hpp"
#include "sim/velodyne/packet.hpp"

namespace sim::velodyne {

// How a point's azimuth between two block azimuths is found.
enum class AzimuthInterpolation : std::uint8_t {
  // By its firing time within the sequence (the manuals' tables), between this sequence's
  // azimuth and the next one's. The default.
  firing_time,
  // As nebula does it (its reference clouds): the difference to the next *block* even where
  // that block is the same sequence (VLS-128 banks, dual-return pairs), so most VLS-128 lasers
  // and dual-return second blocks get no interpolation; VLP-32C, HDL-32E, HDL-64E: unit j at
  // j · 2.304/55.296 of that difference (nebula's VLP-32 decoder; the VLP-32C manual fires
  // the lasers in pairs). For comparing with nebula only.
  nebula,
};

// Where a revolution ends.
enum class CutBy : std::uint8_t {
  // Each point by its own azimuth: a frame holds exactly the points in [cut, cut + 360°).
  point_azimuth,
  // As nebula cuts (its reference clouds): whole packets, the frame ends with the packet whose
  // block azimuths wrap past the cut; only that packet's trailing points within 90° past the
  // cut move to the next frame (VLP-32C, HDL-32E, HDL-64E: none, as nebula's VLP-32 decoder). Lasers with a large rot_correction (VLS-128: up to ±6°) then
  // spill across the cut. For comparing with nebula only.
  packet,
};

// Which returns of a dual-return packet become points. Single-return packets are unaffected.
enum class ReturnFilter : std::uint8_t {
  both,       // the last return, and the strongest when it is another return
  last,       // the last return's blocks only (Packet::return_index 0)
  strongest,  // the strongest's only (or the second strongest when that is the last)
};

struct AssemblerOptions {
  Model model = Model::vlp16;
  double cut_azimuth_deg = 0.0;        // where one revolution ends, degrees (Velodyne azimuth)
  std::optional<float> min_range_m;    // nullopt: the model's limits
  std::optional<float> max_range_m;
  ReturnFilter returns = ReturnFilter::both;
  // Dual return, both: drop the strongest return's point when its distance equals the last's
  // (the sensor repeats a firing's only return).
  bool drop_identical_returns = true;
  // The frame before the first cut (driver start, after a gap) covers part of a revolution.
  bool emit_partial_frames = false;
  AzimuthInterpolation interpolation = AzimuthInterpolation::firing_time;
  CutBy cut_by = CutBy::point_azimuth;
  // Keep only points whose azimuth lies in [min, max] degrees (min > max: the window wraps
  // through 0°); nullopt keeps the whole circle. nebula's tests decode with [0°, 359°].
  struct AzimuthWindow {
    double min_deg = 0;
    double max_deg = 360;
    // nebula also drops every point of a block whose own azimuth is outside the window.
    bool block_azimuth_too = false;
    // nebula's VLP-32 decoder (its VLP-32C, HDL-32E and HDL-64E) tests only each block's
    // azimuth as sent, never the points': their corrected azimuths may lie outside.
    bool block_azimuth_only = false;
  };
  std::optional<AzimuthWindow> azimuth_window;
};

// Velodyne's frames say no more than every family's: stamp_ns is the sensor time of the
// frame's first point, lost_packets are estimated from the packets' timestamps.
using CompletedFrame = lidar::CompletedFrame;

struct PushResult {
  PacketError error = PacketError::none;
  std::optional<CompletedFrame> frame;
  // The packet's sensor time (its µs past the hour, in the hour nearest the reference), for the
  // clock check against its arrival; nullopt when it was rejected.
  std::optional<std::int64_t> packet_ns;
};

// lidar::AssemblerCounters (malformed: cut short, bad flags, azimuth or return mode;
// lost_packets from timestamp gaps) and what only Velodyne sees.
struct AssemblerCounters : lidar::AssemblerCounters {
  std::uint64_t wrong_model = 0;    // another model's (or another vendor's) packet
  std::array<std::uint64_t, packet_error_count> rejected{};
};

// The packet's time: `timestamp_us` past the top of the hour, in the hour that puts it closest
// to `reference_ns` (the host's receive time, or a capture's timestamp), ns since the epoch.
std::int64_t packet_time_ns(std::uint32_t timestamp_us, std::int64_t reference_ns) noexcept;

class FrameAssembler {
 public:
  // Fails (one sentence) when the calibration's laser count is not the model's or the range
  // limits are inverted.
  static Expected<FrameAssembler> create(Calibration calibration, AssemblerOptions options);

  // Where the frame's points go; call before the first push and after every completed frame.
  void set_output(std::span<LidarPoint> output) noexcept;

  // Decodes one UDP payload. `time_reference_ns` picks the hour of the packet's timestamp
  // (0: host_receive_ns). At most one frame completes per call.
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns,
                  std::int64_t time_reference_ns = 0) noexcept;

  // The frame in progress as a partial frame (end of a recording); nullopt when empty.
  std::optional<CompletedFrame> finish() noexcept;
  // Forget the frame in progress and the loss-detection state (a loop, a silence).
  void reset() noexcept;

  const AssemblerCounters& counters() const noexcept { return counters_; }
  const AssemblerOptions& options() const noexcept { return options_; }
  const Calibration& calibration() const noexcept { return calibration_; }
  std::size_t pending_points() const noexcept { return out_.pending(); }
  // Return mode of the last decoded packet (nullopt before the first).
  std::optional<ReturnMode> return_mode() const noexcept { return last_mode_; }

 private:
  FrameAssembler(Calibration calibration, AssemblerOptions options);

  struct FrameState {
    bool started = false;
    bool whole = false;
    std::int64_t stamp_ns = 0;
    std::int64_t host_ns = 0;
    std::uint32_t packets = 0;
    std::uint32_t lost = 0;
    std::uint32_t dropped = 0;
  };
  // Per block of the packet being decoded: the azimuth its points start from and the azimuth
  // change over one sequence (0.01°).
  struct BlockAzimuth {
    std::uint16_t base = 0;
    float step = 0;
  };

  // cos and sin of one 0.01° step of the azimuth table (one cache line holds both).
  struct CosSin {
    float cos;
    float sin;
  };
  // Everything about the lasers the 32 units of a block of bank b (block flag) fire that does
  // not change per point, computed once, as one array per term (structure of arrays) so the
  // loops over a block's 32 units compile to vector instructions. The HDL-64E's terms are zero,
  // and its intensity model the identity, for lasers without them: the full formulas then give
  // exactly the plain result.
  template <typename T>
  using PerUnit = std::array<T, units_per_block>;
  struct BankGeometry {
    PerUnit<float> fraction{};          // of the azimuth step between sequences at which it fires
    PerUnit<double> rot_centi{};        // rot_correction in 0.01° (double: the rounding matches nebula)
    PerUnit<float> cos_vert{};
    PerUnit<float> sin_vert{};
    PerUnit<float> dist_correction{};
    PerUnit<std::uint32_t> time_ns{};   // after the block's sequence start (VLP-16: its second one too)
    PerUnit<std::uint16_t> ring{};
    PerUnit<std::uint64_t> tail{};      // a point's bytes 16–23 for a time base of 0: time_ns, ring
    PerUnit<float> vert_offset{};       // HDL-64E model: optical-centre offsets, two-point correction
    PerUnit<float> horiz_offset{};
    PerUnit<float> two_point_dc{};
    PerUnit<float> two_point_dx{};
    PerUnit<float> two_point_dy{};
    PerUnit<double> focal_term{};       // intensity model: 256·(1 − focal_distance/13100)²
    PerUnit<double> focal_slope{};
    PerUnit<double> min_intensity{};
    PerUnit<double> max_intensity{};
  };
  // A point's first 16 bytes, as LidarPoint has them.
  struct Xyzi {
    float x;
    float y;
    float z;
    float intensity;
  };
  // The sin/cos table index (0.01°) and entry of each unit of the block last decoded, and what
  // they follow from: the next block with the same bank and azimuths (the other block of a
  // dual-return pair) reuses them instead of computing them again.
  struct BlockTrig {
    unsigned bank = banks;              // none yet
    float base = 0;
    float step = 0;
    PerUnit<std::int32_t> azimuth{};
    PerUnit<CosSin> trig{};
  };
  // A block's 32 decoded units before they are stored, so computing them (vector instructions)
  // and storing the kept ones (two copies a point) are separate loops.
  struct BlockPoints {
    PerUnit<Xyzi> xyzi;
    PerUnit<std::uint32_t> keep;        // 1: a return within the range limits, not a repeat
  };
  // One block as the per-point decoding needs it, with the limits copied so the point loop
  // reads no member the output writes could alias. block_context sets every field (no
  // initialisers: zeroing it first, a "rep stos" per block, cost about 4 % of the decode).
  struct BlockContext {
    const std::uint8_t* units;            // 32 × (distance, reflectivity)
    const std::uint8_t* partner;          // the pair's other return to compare, or none
    const BankGeometry* geometry;         // the block's bank
    unsigned bank;
    const CosSin* trig;
    float base;                           // azimuth the points start from and step, 0.01°
    float step;
    float unit_m;
    float min_range_m;
    float max_range_m;
    std::int32_t real_azimuth;            // the sequence's own azimuth
    std::int64_t ns;                      // the sequence's start, ns since the epoch
    std::int64_t time_base;               // in place: ns after the frame's stamp
    std::uint8_t return_index;
  };

  static const CosSin* shared_trig_table();
  void block_azimuths(const Packet& packet, std::array<BlockAzimuth, blocks_per_packet>& out) noexcept;
  void nebula_block_azimuths(const Packet& packet, std::array<BlockAzimuth, blocks_per_packet>& out) const noexcept;
  void build_unit_geometry() noexcept;
  void decode_block(const Packet& packet, unsigned block, const BlockAzimuth& azimuth,
                    std::int64_t block_position, std::int64_t packet_ns, std::int64_t host_ns) noexcept;
  template <bool Full, bool Intensity>
  void decode_block_as(const Packet& packet, unsigned block, const BlockAzimuth& azimuth,
                       std::int64_t block_position, std::int64_t packet_ns, std::int64_t host_ns) noexcept;
  bool block_context(const Packet& packet, unsigned block, const BlockAzimuth& azimuth, std::int64_t packet_ns,
                     BlockContext& out) const noexcept;
  bool fits_in_place(BlockContext& block, std::int64_t block_position) const noexcept;
  template <bool Full, bool Intensity>
  void decode_in_place(const BlockContext& block) noexcept;
  template <bool Full, bool Intensity>
  void decode_point_by_point(const BlockContext& block, std::int64_t block_position, std::int64_t host_ns) noexcept;
  static void azimuth_indices(const BlockContext& block, PerUnit<std::int32_t>& out) noexcept;
  [[gnu::always_inline]] static inline bool flag_points(const BlockContext& block, PerUnit<std::int32_t>& raw, PerUnit<float>& distance,
                                                        PerUnit<float>& intensity, PerUnit<std::uint32_t>& keep) noexcept;
  template <bool Full, bool Intensity>
  static bool decode_units(const BlockContext& block, BlockTrig& trig, BlockPoints& out) noexcept;
  static void full_model_points(const BankGeometry& g, const PerUnit<float>& distance, const PerUnit<float>& intensity,
                                const PerUnit<CosSin>& trig, BlockPoints& out) noexcept;
  void emit(const LidarPoint& point, std::int64_t position, std::int64_t point_ns,
            std::int64_t host_ns) noexcept;
  void start(FrameState& frame, std::int64_t point_ns, std::int64_t host_ns, bool whole) noexcept;
  void complete(PushResult& result) noexcept;
  void drop_points(FrameState& frame, std::size_t points) noexcept;
  bool starts_whole(std::int64_t revolution) const noexcept;
  void move_packet_tail_to_next() noexcept;
  bool in_window(std::int32_t azimuth_centi) const noexcept;
  void abandon_current() noexcept;
  void count_packet(std::int64_t packet_ns, const Packet& packet) noexcept;

  static constexpr std::size_t max_lasers = 128;
  static constexpr std::size_t banks = 4;

  Calibration calibration_;
  AssemblerOptions options_;
  const ModelInfo* info_ = nullptr;
  float min_range_m_ = 0;
  float max_range_m_ = 0;
  std::uint16_t cut_centi_ = 0;
  bool windowed_ = false;
  bool window_points_ = false;  // each point's azimuth is tested (not block_azimuth_only)
  std::int32_t window_min_centi_ = 0;
  std::int32_t window_max_centi_ = 0;
  const CosSin* trig_table_ = nullptr;  // 36,000 entries: 0.00°…359.99° (shared by the process)
  std::array<BankGeometry, banks> banks_{};
  BlockTrig block_trig_;
  bool full_model_ = false;        // some laser has HDL-64E offsets or a two-point correction
  bool intensity_model_ = false;   // some laser has the focal intensity model
  // Blocks whose points all land in the frame in progress are decoded straight into the output
  // without a branch per point; only with the default interpolation and cut, no azimuth window.
  bool in_place_ = false;
  std::uint32_t max_unit_time_ns_ = 0;
  double min_point_delta_centi_ = 0;  // smallest (interpolation − rot_correction) any point gets
  double max_point_delta_centi_ = 0;

  FrameState current_;
  FrameState next_;
  std::int64_t current_revolution_ = 0;
  // current_'s points in the caller's span, when attached; the carry-over holds next_'s points
  // then, current_'s while no span is attached.
  lidar::FrameOutput out_;
  bool next_is_whole_ = false;     // the frame after a completed one starts at the cut

  bool have_block_ = false;
  std::int64_t block_revolution_ = 0;
  std::uint16_t last_phase_ = 0;
  std::int64_t last_block_position_ = 0;
  std::int64_t first_position_ = 0;  // of the first block since the start (or a reset)
  float last_step_ = 0;               // azimuth per sequence, learned, for the packet's last blocks
  std::uint16_t last_packet_azimuth_ = 0;
  std::int64_t last_packet_ns_ = 0;
  // CutBy::packet: the previous packet's first block phase, and where this packet's points
  // start in the output with their azimuth phase (for moving the tail to the next frame).
  std::uint16_t last_packet_phase_ = 0;
  std::uint32_t packets_since_cut_ = 0;
  std::size_t packet_first_point_ = 0;
  std::array<std::uint16_t, blocks_per_packet * units_per_block> packet_point_phase_{};
  std::size_t packet_points_ = 0;
  bool have_packet_ = false;
  std::optional<ReturnMode> last_mode_;
  std::uint64_t frame_index_ = 0;
  AssemblerCounters counters_;
};

}  // namespace sim::velodyne
