// SPDX-License-Identifier: Apache-2.0
// FrameAssembler ("scan cutter"): turns a stream of Hesai UDP payloads into one frame per
// revolution, decoding straight into a span the caller owns (a SIM writer's loaned slot).
// The live driver and the pcap replay use this same object.
//
//   auto assembler = FrameAssembler::create(calibration, options).value();
//   auto loan = writer.loan();
//   assembler.set_output(loan.as<sim::LidarPoint>());
//   for each UDP payload:
//     PushResult r = assembler.push(payload, host_receive_ns);
//     if (r.frame) {                                       // a revolution is complete
//       std::move(loan).commit(r.frame->point_count * sizeof(sim::LidarPoint), r.frame->stamp_ns);
//       loan = writer.loan();
//       assembler.set_output(loan.as<sim::LidarPoint>());  // before the next push
//     }
//
// Near the cut two frames are open at once: with per-point cutting (the default) a point
// belongs to the revolution its own azimuth (block azimuth + channel offset) falls in, so the
// firings just before the cut already hold points of the next frame and those just after it
// still hold points of the previous one. Points of the frame that has no span yet go to a small
// carry-over buffer, sized at create() for the calibration's offset spread plus two packets,
// which set_output() copies to the front of the next span. Nothing is allocated after create().
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/hesai/calibration.hpp"
#include "sim/hesai/model.hpp"
#include "sim/hesai/packet.hpp"
#include "sim/lidar/assembler_counters.hpp"
#include "sim/lidar/completed_frame.hpp"
#include "sim/lidar/frame_output.hpp"
#include "sim/lidar_point.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

namespace detail {
// FrameAssembler::decode_group's working state for one firing group (frame_assembler.cpp).
struct GroupTargets;  // which frame each channel's points go to
struct GroupSinks;    // where those frames' points are written
}  // namespace detail

// Where a revolution ends.
enum class CutBy : std::uint8_t {
  // Each point by its own azimuth (block azimuth + channel offset): a frame holds exactly the
  // points with azimuth in [cut, cut + 360°). This is what nebula's reference clouds do.
  point_azimuth,
  // Whole firings by block azimuth: simpler, but points of channels with an azimuth offset
  // spill across the cut by up to that offset (Pandar64: 5.2°, XT32: under 0.1°).
  block_azimuth,
};

// Every choice the decoder makes is an option; the defaults reproduce nebula's reference
// clouds (see docs/hesai.md and tests/drivers/hesai/data/NOTICE.md).
struct AssemblerOptions {
  Model model = Model::pandar64;
  // A new frame starts where the azimuth reaches this angle (degrees, Hesai frame).
  double cut_azimuth_deg = 0.0;
  CutBy cut_by = CutBy::point_azimuth;
  // Points closer or farther than this are dropped; nullopt = the model's own limits.
  std::optional<float> min_range_m;
  std::optional<float> max_range_m;
  // A raw distance of 0 means "no return"; keeping it puts a point at the origin.
  bool drop_zero_distance = true;
  // Multi-return groups: of returns identical in distance and reflectivity keep only the last.
  bool drop_identical_returns = true;
  // Multi-return groups: drop a non-last return within this distance of another return of its
  // group (0 disables).
  float multi_return_distance_threshold_m = 0.1f;
  // The frame before the first cut (driver start, after a restart) covers part of a
  // revolution; publish it (whole = false) or drop it.
  bool emit_partial_frames = false;
  // Optional firing-time file: replaces the built-in channel firing times, and with
  // firetime_azimuth_compensation adds firetime·rpm·6e-6 degrees to each point's azimuth
  // (Hesai SDK 2 behaviour; nebula does not do it).
  std::optional<FiretimeCorrection> firetimes;
  bool firetime_azimuth_compensation = false;
};

// lidar::CompletedFrame's fields as Hesai fills them: stamp_ns is the sensor UTC of the frame's
// earliest firing; packets are those that contributed points or firings; lost_packets come
// from the UDP sequence or, without one, azimuth gaps; whole = started at a cut and ended at
// the next one.
struct CompletedFrame : lidar::CompletedFrame {
  std::uint16_t motor_rpm = 0;  // motor speed the frame's last packet reported
  // Models with a functional-safety section (QT128): the worst state any packet of the frame
  // reported, with that packet's fault code. A user drops or flags frames that are not
  // `normal` (or `initialization`, while the sensor starts).
  std::optional<FunctionalSafety> safety;
};

struct PushResult {
  PacketError error = PacketError::none;  // why the packet was rejected (counted), or none
  std::optional<CompletedFrame> frame;    // set when this packet completed a frame
  // The packet's own sensor time (its tail's date and µs), for the clock check against its
  // arrival; nullopt when it was rejected.
  std::optional<std::int64_t> packet_ns;
};

// lidar::AssemblerCounters (packets, malformed, lost_packets from UDP sequence or azimuth
// gaps, frames, partial_frames_dropped, dropped_points) and what only Hesai sees.
struct AssemblerCounters : lidar::AssemblerCounters {
  std::uint64_t crc_errors = 0;       // rejected: a CRC did not match (QT128), not in malformed
  std::uint64_t wrong_model = 0;      // rejected: another Hesai model on the port
  std::uint64_t out_of_order = 0;     // sequence went backwards or repeated
  std::uint64_t frames_without_output = 0;   // completed while set_output() had not been called
  std::array<std::uint64_t, packet_error_count> rejected{};  // by PacketError value
};

class FrameAssembler {
 public:
  // Fails (one sentence) when the calibration's channel count is not the model's, the range
  // limits are inverted or negative, or the firing-time file has the wrong channel count (or
  // is given for the QT128, whose two firing loops one column cannot describe).
  static Expected<FrameAssembler> create(Calibration calibration, AssemblerOptions options);

  // The span the following points go to. Call once before the first push and again after
  // every completed frame (and finish); the points already decoded for the new frame are copied
  // to its front. The span must stay valid until the next completed frame. Called in the middle
  // of a frame, it restarts that frame's storage (the frame is then not a whole revolution).
  void set_output(std::span<LidarPoint> output) noexcept;

  // Decodes one UDP payload. At most one frame completes per call; its points are the front
  // of the span last given to set_output, which the assembler no longer touches afterwards.
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept;

  // Returns the frame in progress as a (partial, whole = false) frame and starts
  // over, e.g. at the end of a recording; like a completed frame, the span then belongs to the
  // caller again. nullopt when it holds no firing or has no span.
  std::optional<CompletedFrame> finish() noexcept;

  // Forget the frame in progress and the loss-detection state (a new recording, a loop). The
  // output span, if any, stays attached and is refilled from its start.
  void reset() noexcept;

  const AssemblerCounters& counters() const noexcept { return counters_; }
  // What the last decoded packet said about the sensor, for status lines: its motor speed
  // (0 before the first packet) and functional-safety state (models that send one).
  std::uint16_t motor_rpm() const noexcept { return last_rpm_; }
  const std::optional<FunctionalSafety>& functional_safety() const noexcept { return last_safety_; }
  const AssemblerOptions& options() const noexcept { return options_; }
  const Calibration& calibration() const noexcept { return calibration_; }
  // Points the frame in progress holds so far.
  std::size_t pending_points() const noexcept;
  // How long, at the motor speed the last packet reported, until a packet can complete the
  // frame in progress (0 when the next one may). nullopt before the first packet or when the
  // motor speed is 0. A live driver sleeps through this time instead of waking per packet.
  std::optional<std::int64_t> time_to_cut_ns() const noexcept;

 private:
  FrameAssembler(Calibration calibration, AssemblerOptions options);

  struct FrameState {
    bool started = false;
    bool whole = false;             // began at the cut
    std::int64_t stamp_ns = 0;
    std::int64_t host_ns = 0;
    std::uint64_t last_packet = 0;  // packet counter value that last contributed
    std::uint32_t packets = 0;
    std::uint32_t lost = 0;
    std::uint32_t dropped = 0;
    std::uint16_t rpm = 0;
    std::optional<FunctionalSafety> safety;  // worst seen
  };

  void begin(FrameState& frame, const Packet& packet, unsigned block, std::int64_t host_ns,
             bool whole) noexcept;
  void close_current(PushResult& result, bool ended_at_cut) noexcept;
  void drop_points(FrameState& frame, std::size_t points) noexcept;
  // push()'s steps.
  void count_rejected(PacketError error) noexcept;
  std::int64_t revolution_of_group(std::uint16_t azimuth, std::uint16_t phase) noexcept;
  void close_frame_before(const Packet& packet, unsigned block, std::int64_t group_revolution,
                          std::uint16_t phase, std::int64_t host_ns, PushResult& result) noexcept;
  void decode_group(const Packet& packet, unsigned first_block, std::int64_t group_revolution,
                    std::uint16_t phase, std::int64_t host_ns) noexcept;
  // decode_group's steps around the point computation (frame_assembler.cpp).
  detail::GroupTargets frames_of_channels(std::uint16_t phase,
                                          std::int64_t group_revolution) const noexcept;
  detail::GroupSinks open_sinks(const detail::GroupTargets& targets, const Packet& packet,
                                unsigned first_block, std::int64_t host_ns) noexcept;
  void note_packet(FrameState& frame, const Packet& packet) noexcept;
  void store_sinks(const detail::GroupSinks& sinks) noexcept;
  void count_loss(const Packet& packet) noexcept;
  void update_azimuth_offsets(std::uint16_t rpm) noexcept;

  static constexpr std::size_t max_channels = 128;

  Calibration calibration_;
  AssemblerOptions options_;
  float min_range_m_ = 0;
  float max_range_m_ = 0;
  std::uint16_t cut_centi_deg_ = 0;
  unsigned channels_ = 0;
  // Per channel, computed once (or when the rpm changes, with firing-time compensation):
  // the point is rotated by the block azimuth and then by the channel's azimuth offset, so the
  // hot loop needs no trigonometry.
  std::array<float, max_channels> cos_elevation_{};
  std::array<float, max_channels> sin_elevation_{};
  std::array<float, max_channels> cos_azimuth_offset_{};
  std::array<float, max_channels> sin_azimuth_offset_{};
  // Offset used to decide which revolution a point belongs to, 0.01° (0 when cutting by block).
  std::array<double, max_channels> cut_offset_centi_{};
  double min_cut_offset_centi_ = 0;
  double max_cut_offset_centi_ = 0;
  // Per firing loop (two on the QT128, see Packet::firing_loop), per channel.
  std::array<std::array<std::int32_t, max_channels>, 2> channel_offset_ns_{};
  // Their range per loop: when a group's time base plus this range fits a point's uint32
  // time offset, no point of the group needs the clamp.
  std::array<std::int32_t, 2> min_channel_offset_ns_{};
  std::array<std::int32_t, 2> max_channel_offset_ns_{};
  std::int32_t earliest_channel_offset_ns_ = 0;
  std::uint16_t compensated_rpm_ = 0;

  // The frame in progress (revolution current_revolution_) and, near the cut, the next one.
  FrameState current_;
  FrameState next_;
  std::int64_t current_revolution_ = 0;
  // current_'s points in the caller's span, when attached; the carry-over holds next_'s points
  // then, current_'s while no span is attached.
  lidar::FrameOutput out_;

  bool have_last_ = false;           // a previous firing group exists (cut and gap detection)
  std::int64_t block_revolution_ = 0;  // revolutions the block azimuth has wrapped at the cut
  std::uint16_t last_phase_ = 0;     // last group's block azimuth relative to the cut, 0.01°
  std::uint16_t last_azimuth_ = 0;   // last group's block azimuth, 0.01°
  std::uint16_t azimuth_step_ = 0;   // between firing groups, learned inside packets
  std::uint16_t last_rpm_ = 0;       // motor speed of the last decoded packet
  std::optional<FunctionalSafety> last_safety_;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  std::uint64_t packet_counter_ = 0;
  std::uint64_t frame_index_ = 0;
  AssemblerCounters counters_;
};

}  // namespace sim::hesai
