// SPDX-License-Identifier: Apache-2.0
// FrameAssembler: turns an Ouster sensor's lidar packets into one point frame per rotation,
// decoding straight into a span the caller owns (a SIM writer's loaned slot). The live driver
// and the pcap replay use this same object (through LidarStream).
//
//   auto assembler = FrameAssembler::create(metadata, options).value();
//   assembler.set_output(loan.as<sim::LidarPoint>());
//   for each lidar payload:
//     PushResult r = assembler.push(payload, host_receive_ns);
//     if (r.frame) { commit r.frame->point_count points; set_output(next loan) before the next push }
//
// A frame is the columns of one frame_id. It completes on the packet that holds the column
// window's last column, or (when that packet was lost) on the first packet of the next frame,
// which then waits in a one-packet buffer until set_output() gives the next span. A window that
// wraps through column 0 arrives as columns 0 … end, then start … W − 1: it begins at column 0
// and completes at column W − 1. A packet of an older frame (late) is dropped and counted.
//
// Points are in the sensor frame as ouster-ros publishes them by default: the metadata's
// beam angles and lidar_origin_to_beam_origin give each pixel's direction and origin in the
// lidar frame (firmware user manual, "Lidar Range to XYZ"), lidar_to_sensor_transform moves
// them to the sensor frame; metres. Every pixel of a column has the column's timestamp.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "sim/lidar/assembler_counters.hpp"
#include "sim/lidar/completed_frame.hpp"
#include "sim/lidar_point.hpp"
#include "sim/ouster/metadata.hpp"
#include "sim/ouster/packet.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

enum class CloudLayout : std::uint8_t {
  // H × W points per return, row-major by beam, destaggered (column c of row u holds the pixel
  // whose azimuth is column c's, as ouster-ros's organised cloud); no return: x = y = z = 0.
  // Dual profiles: the second return's H × W image follows the first's.
  organized,
  // Only pixels with a return inside the range limits, in packet order.
  dense,
};

// Which of the pixel's channels goes into LidarPoint::intensity.
enum class IntensityField : std::uint8_t {
  automatic,     // signal when the profile has it (ouster-ros's "intensity"), else reflectivity
  signal,        // photons of the return
  reflectivity,  // calibrated reflectivity, 0–255
  near_ir,       // ambient near-infrared photons
};

struct AssemblerOptions {
  CloudLayout layout = CloudLayout::organized;
  IntensityField intensity = IntensityField::automatic;
  bool first_return_only = false;  // dual profiles: drop the second return
  float min_range_m = 0;           // closer returns are dropped (dense) or zeroed (organised)
  float max_range_m = 0;           // 0: no limit
  // Publish frames that did not start at the column window's first column (driver start).
  bool emit_partial_frames = false;
};

// lidar::CompletedFrame's fields as Ouster fills them: stamp_ns is the frame's first valid
// column (sensor clock); whole = began at the window's first column. What was lost is counted in
// columns, the sensor's own unit: missing_columns; lost_packets is the same rounded up to whole
// packets (columns_per_packet), as AssemblerCounters::lost_packets adds it up, and 0 for a
// partial frame (its missing columns are mostly those before it began).
struct CompletedFrame : lidar::CompletedFrame {
  std::uint32_t frame_id = 0;         // the sensor's frame counter
  std::uint32_t missing_columns = 0;  // columns of the window that never came (lost packets)
  std::uint32_t invalid_columns = 0;  // columns the sensor marked invalid (status)
};

struct PushResult {
  PacketError error = PacketError::none;
  std::optional<CompletedFrame> frame;
  // The sensor time of the packet's first valid column, for the clock check against its
  // arrival; nullopt when it was rejected or has no valid column.
  std::optional<std::int64_t> packet_ns;
};

// lidar::AssemblerCounters (malformed: every PacketError; lost_packets from missing columns of
// whole frames; dropped_points: no output span, or the span was too small) and what only
// Ouster sees.
struct AssemblerCounters : lidar::AssemblerCounters {
  std::uint64_t duplicate_columns = 0;
  std::uint64_t invalid_columns = 0;
  std::uint64_t late_packets = 0;  // of a frame already closed or older: dropped (ouster-sdk too)
  std::uint64_t frames_without_output = 0;
  std::array<std::uint64_t, packet_error_count> rejected{};  // by PacketError
  std::size_t last_rejected_size = 0;  // payload size of the last wrong_size packet
};

namespace detail {

// The geometry, precomputed in double and kept in float (see build_geometry()). The direction
// of pixel (u, m) in the sensor frame, in metres per millimetre of range, is
//   d = a_u·E_m + b_u·F_m + g_u
// (angle addition: the beam's azimuth offset and altitude, the column's encoder angle), and the
// pixel of range r lies at (r − n)·d + O_m. Per beam and per column, not per pixel: a few
// kilobytes that stay in L1 instead of a 12-byte-a-pixel table read once a frame (3 MB at 128×2048).
struct BeamGeometry {
  float a, b;        // cos φ·cos θa, cos φ·sin θa
  float gx, gy, gz;  // sin φ · R·(0, 0, 1) / 1000
};
struct ColumnGeometry {
  float ex, ey, ez;  // R·(cos θe, sin θe, 0) / 1000
  float fx, fy, fz;  // R·(−sin θe, cos θe, 0) / 1000
  float ox, oy, oz;  // (R·(T03·cos θe, T03·sin θe, T23) + t) / 1000: the beams' origin, metres
};

struct PacketColumns;  // one packet's accepted columns (frame_assembler.cpp)

}  // namespace detail

class FrameAssembler {
 public:
  // Fails (one sentence) for inverted, negative or non-finite range limits, beam tables of the
  // wrong length, more than max_columns_per_packet columns per packet, or signal asked of a
  // profile without it.
  static Expected<FrameAssembler> create(const Metadata& metadata, AssemblerOptions options);

  static constexpr unsigned max_columns_per_packet = PacketFormat::max_columns_per_packet;

  // Points one frame can hold: H × W × returns.
  std::size_t max_points() const noexcept;

  void set_output(std::span<LidarPoint> output) noexcept;
  PushResult push(std::span<const std::uint8_t> payload, std::int64_t host_receive_ns) noexcept;
  // The frame in progress as a finished frame (end of a recording); nullopt when empty or
  // partial without emit_partial_frames.
  std::optional<CompletedFrame> finish() noexcept;
  // Forget the frame in progress (a loop, a silence).
  void reset() noexcept;

  const AssemblerCounters& counters() const noexcept { return counters_; }
  const Metadata& metadata() const noexcept { return metadata_; }
  const AssemblerOptions& options() const noexcept { return options_; }
  unsigned returns() const noexcept { return returns_; }

 private:
  using BeamGeometry = detail::BeamGeometry;
  using ColumnGeometry = detail::ColumnGeometry;
  using PacketColumns = detail::PacketColumns;

  FrameAssembler(const Metadata& metadata, AssemblerOptions options);
  void build_geometry();
  void begin(const LidarPacket& packet, std::int64_t host_ns) noexcept;
  void decode(const LidarPacket& packet) noexcept;
  template <Profile P>
  void decode_columns(const LidarPacket& packet) noexcept;
  void accept_columns(const LidarPacket& packet, PacketColumns& out) noexcept;
  template <Profile P, bool Dual>
  void decode_beams(const PacketColumns& columns) noexcept;
  template <Profile P, bool Dual, IntensityField F>
  void decode_beams_as(const PacketColumns& columns) noexcept;
  std::optional<CompletedFrame> close() noexcept;
  unsigned first_column() const noexcept;
  unsigned last_column() const noexcept;
  bool late(std::uint32_t frame_id) const noexcept;
  void fill_missing_columns() noexcept;

  Metadata metadata_;
  AssemblerOptions options_;
  unsigned beams_ = 0;
  unsigned columns_ = 0;
  unsigned returns_ = 1;
  std::size_t image_points_ = 0;  // H × W
  // Returns inside [min_range_mm_, max_range_mm_] make points; 0 (no return) never does.
  std::int32_t min_range_mm_ = 1;
  std::int32_t max_range_mm_ = 0;
  IntensityField intensity_ = IntensityField::signal;
  std::vector<BeamGeometry> beam_geometry_;      // H
  std::vector<ColumnGeometry> column_geometry_;  // W
  float beam_origin_mm_ = 0;                     // n
  // Destaggering: row u's column m lands in column (m + row_shift_[u]) mod W.
  std::vector<unsigned> row_shift_;
  std::size_t organized_index(unsigned u, unsigned m) const noexcept {
    unsigned c = m + row_shift_[u];
    if (c >= columns_) c -= columns_;
    return std::size_t{u} * columns_ + c;
  }

  // The frame in progress.
  bool open_ = false;
  bool whole_ = false;
  std::uint32_t frame_id_ = 0;  // after close(): the frame just closed
  bool have_frame_id_ = false;
  std::int64_t stamp_ns_ = 0;
  bool have_stamp_ = false;
  std::int64_t host_ns_ = 0;
  std::uint32_t packets_ = 0;
  std::uint32_t invalid_columns_ = 0;
  std::uint64_t dropped_points_ = 0;  // found no room in the span
  std::vector<std::uint8_t> received_;  // per measurement_id
  std::size_t dense_count_ = 0;

  std::span<LidarPoint> output_;
  bool attached_ = false;
  // The first packet of the next frame when it arrived before the last one of this frame.
  std::vector<std::uint8_t> pending_;
  std::size_t pending_size_ = 0;
  std::int64_t pending_host_ns_ = 0;
  std::uint64_t frame_index_ = 0;
  AssemblerCounters counters_;
};

}  // namespace sim::ouster
