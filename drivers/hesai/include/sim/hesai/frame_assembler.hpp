// SPDX-License-Identifier: Apache-2.0
// FrameAssembler ("scan cutter"): turns a stream of Hesai UDP payloads into one frame per
// revolution, decoding straight into a span the caller owns (a SIM writer's loaned slot).
// The live driver and the pcap replay use this same object.
//
//   FrameAssembler assembler{calibration, options};        // from FrameAssembler::create
//   auto loan = writer.loan();
//   assembler.set_output(loan.as<sim::LidarPoint>());
//   for each UDP payload:
//     PushResult r = assembler.push(payload, host_receive_ns);
//     if (r.frame) {                                       // a revolution is complete
//       loan.commit(r.frame->point_count * sizeof(sim::LidarPoint), r.frame->stamp_ns);
//       loan = writer.loan();
//       assembler.set_output(loan.as<sim::LidarPoint>());  // before the next push
//     }
//
// The packet that straddles the cut azimuth is decoded in two parts: the blocks before the cut
// go to the completed frame, the blocks after it into a small fixed carry-over buffer (one
// packet at most) that set_output() copies to the front of the next span. Nothing is allocated
// after create().
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "sim/hesai/calibration.hpp"
#include "sim/hesai/model.hpp"
#include "sim/hesai/packet.hpp"
#include "sim/lidar_point.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

// Every choice the decoder makes is an option; the defaults reproduce nebula's reference
// clouds (see docs/hesai.md and ../shared/data/lidar/SOURCES.md).
struct AssemblerOptions {
  Model model = Model::pandar64;
  // A new frame starts at the first firing whose block azimuth reaches this angle.
  double cut_azimuth_deg = 0.0;
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
  // revolution; publish it (whole_revolution = false) or drop it.
  bool emit_partial_frames = false;
  // Optional firing-time file: replaces the built-in channel firing times, and with
  // firetime_azimuth_compensation adds firetime·rpm·6e-6 degrees to each point's azimuth
  // (Hesai SDK 2 behaviour; nebula does not do it).
  std::optional<FiretimeCorrection> firetimes;
  bool firetime_azimuth_compensation = false;
};

struct CompletedFrame {
  std::size_t point_count = 0;        // points written at the front of the output span
  std::int64_t stamp_ns = 0;          // sensor UTC of the frame's first firing, ns since epoch
  std::int64_t host_receive_ns = 0;   // host receive time of the frame's first packet
  std::uint64_t index = 0;            // 0, 1, 2… frames completed by this assembler
  std::uint32_t packets = 0;          // packets that contributed points or firings
  std::uint32_t lost_packets = 0;     // packets missing inside this frame (sequence/azimuth)
  std::uint32_t dropped_points = 0;   // points that did not fit in the output span
  bool whole_revolution = true;       // started at a cut and ended at the next one
};

struct PushResult {
  PacketError error = PacketError::none;  // why the packet was rejected (counted), or none
  std::optional<CompletedFrame> frame;    // set when this packet completed a frame
};

struct AssemblerCounters {
  std::uint64_t packets = 0;          // decoded
  std::uint64_t malformed = 0;        // rejected: cut short, bad field values
  std::uint64_t wrong_model = 0;      // rejected: another Hesai model on the port
  std::uint64_t lost_packets = 0;     // estimated from UDP sequence or azimuth gaps
  std::uint64_t out_of_order = 0;     // sequence went backwards or repeated
  std::uint64_t frames = 0;           // completed and returned
  std::uint64_t partial_frames_dropped = 0;  // before the first cut (emit_partial_frames off)
  std::uint64_t frames_without_output = 0;   // completed while set_output() had not been called
  std::uint64_t dropped_points = 0;   // output span full, or no output set
  std::array<std::uint64_t, packet_error_count> rejected{};  // by PacketError value
};

class FrameAssembler {
 public:
  // Fails (one sentence) when the calibration's channel count is not the model's, the range
  // limits are inverted or negative, or the firing-time file has the wrong channel count.
  static Expected<FrameAssembler> create(Calibration calibration, AssemblerOptions options);

  // The span the following points go to. Call once before the first push and again after
  // every completed frame; the carried-over points of the straddling packet are copied to its
  // front. The span must stay valid until the next completed frame.
  void set_output(std::span<LidarPoint> output) noexcept;

  // Decodes one UDP payload. At most one frame completes per call; its points are the front
  // of the span last given to set_output, which the assembler no longer touches afterwards.
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept;

  // Returns the frame in progress as a (partial) frame and starts over, e.g. at the end of a
  // recording. nullopt when it holds no firing.
  std::optional<CompletedFrame> flush() noexcept;

  // Forget the frame in progress and the loss-detection state (a new recording, a loop).
  void reset() noexcept;

  const AssemblerCounters& counters() const noexcept { return counters_; }
  const AssemblerOptions& options() const noexcept { return options_; }
  const Calibration& calibration() const noexcept { return calibration_; }
  // Points the frame in progress holds so far.
  std::size_t pending_points() const noexcept;

 private:
  FrameAssembler(Calibration calibration, AssemblerOptions options);

  struct FrameState {
    bool started = false;
    bool whole = false;         // began at the cut azimuth
    std::int64_t stamp_ns = 0;
    std::int64_t host_ns = 0;
    std::uint32_t packets = 0;
    std::uint32_t lost = 0;
    std::uint32_t dropped = 0;
  };

  void start_frame(const Packet& packet, unsigned block, std::int64_t host_ns, bool whole) noexcept;
  void on_cut(PushResult& result) noexcept;
  void decode_group(const Packet& packet, unsigned first_block) noexcept;
  void count_loss(const Packet& packet) noexcept;
  void update_azimuth_offsets(std::uint16_t rpm) noexcept;
  CompletedFrame finish(std::size_t count, bool ended_at_cut) noexcept;
  std::span<LidarPoint> destination() noexcept;
  std::size_t& destination_count() noexcept;

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
  std::array<std::int32_t, max_channels> channel_offset_ns_{};
  std::int32_t earliest_channel_offset_ns_ = 0;
  std::uint16_t compensated_rpm_ = 0;

  std::span<LidarPoint> output_;
  bool output_attached_ = false;
  std::size_t output_count_ = 0;
  FrameState current_;
  bool packet_counted_ = false;

  // Points of the frame in progress while no output is attached: the part of the straddling
  // packet after the cut, until set_output() copies it to the front of the new span.
  std::array<LidarPoint, max_points_per_packet> carry_{};
  std::size_t carry_count_ = 0;

  bool have_last_ = false;           // a previous firing group exists (cut and gap detection)
  std::uint16_t last_phase_ = 0;     // its azimuth relative to the cut, 0.01°
  std::uint16_t last_azimuth_ = 0;   // its block azimuth, 0.01°
  std::uint16_t azimuth_step_ = 0;   // between firing groups, learned inside packets
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  std::uint64_t frame_index_ = 0;
  AssemblerCounters counters_;
};

}  // namespace sim::hesai
