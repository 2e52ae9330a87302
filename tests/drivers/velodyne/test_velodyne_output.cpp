// SPDX-License-Identifier: Apache-2.0
// The output span replaced in the middle of a frame (set_output before the frame completed), on
// synthetic HDL-32E packets (packet_builder.hpp): the points already decoded for the next
// revolution wait in the carry-over and must reach the next revolution's span, not the span
// that replaced the one of the frame in progress (sim/lidar/frame_output.hpp).
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "packet_builder.hpp"
#include "sim/velodyne/velodyne.hpp"

namespace {

using namespace sim::velodyne;
using velodyne_test::DataPacket;

constexpr std::int64_t hour_start_ns = 1'700'000'000'000'000'000 / 3'600'000'000'000 * 3'600'000'000'000;
constexpr unsigned step = 16;  // 0.16° per sequence: 2250 sequences a revolution
// The first block's azimuth: packet 31's last block is at 359.95°, so its later lasers fall past
// the cut (0°) while no block has passed it yet.
constexpr unsigned first_azimuth = 29867;

std::vector<std::vector<std::uint8_t>> hdl32e_packets(unsigned count) {
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned k = 0; k < count; ++k) {
    DataPacket p;
    p.product_id = 0x21;
    p.timestamp_us = static_cast<std::uint32_t>(1'000'000 + k * 553);
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned seq = k * 12 + b;
      p.blocks[b].azimuth = static_cast<std::uint16_t>((first_azimuth + seq * step) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {static_cast<std::uint16_t>(3000 + l), 10};
    }
    packets.push_back(p.bytes());
  }
  return packets;
}

FrameAssembler hdl32e_assembler() {
  auto calibration = Calibration::load(std::string(VELODYNE_CALIBRATION_DIR) + "/HDL32.yaml");
  EXPECT_TRUE(calibration) << calibration.error().message;
  AssemblerOptions options;
  options.model = Model::hdl32e;
  options.emit_partial_frames = true;  // the first frame, from 298.67°, completes too
  auto assembler = FrameAssembler::create(std::move(calibration.value()), options);
  EXPECT_TRUE(assembler) << assembler.error().message;
  return std::move(assembler.value());
}

std::optional<CompletedFrame> push(FrameAssembler& a, const std::vector<std::uint8_t>& packet) {
  return a.push(packet, hour_start_ns + 1'000'000'000).frame;
}

TEST(VelodyneOutput, a_span_replaced_mid_frame_leaves_the_next_revolution_whole) {
  const auto packets = hdl32e_packets(240);
  // Which packet completes the first (partial) frame, with the span never replaced.
  std::size_t completing = 0;
  {
    FrameAssembler a = hdl32e_assembler();
    std::vector<sim::LidarPoint> span(100'000);
    a.set_output(span);
    while (completing < packets.size() && !push(a, packets[completing])) ++completing;
    ASSERT_LT(completing, packets.size());
  }

  FrameAssembler a = hdl32e_assembler();
  std::vector<sim::LidarPoint> first(100'000), replacement(100'000), next(100'000);
  a.set_output(first);
  for (std::size_t k = 0; k < completing; ++k) ASSERT_FALSE(push(a, packets[k]));
  const std::size_t in_first = a.pending_points();
  ASSERT_GT(in_first, 0U);
  a.set_output(replacement);  // mid-frame: the frame's points so far stay in `first`
  const auto partial = push(a, packets[completing]);
  ASSERT_TRUE(partial);
  EXPECT_FALSE(partial->whole);
  EXPECT_EQ(partial->dropped_points, in_first);
  EXPECT_EQ(a.counters().dropped_points, in_first);

  // The next revolution: every laser once per 0.16°, including the points decoded before the
  // span was replaced.
  a.set_output(next);
  std::optional<CompletedFrame> revolution;
  for (std::size_t k = completing + 1; k < packets.size() && !revolution; ++k) revolution = push(a, packets[k]);
  ASSERT_TRUE(revolution);
  EXPECT_TRUE(revolution->whole);
  EXPECT_EQ(revolution->point_count, 2250U * 32U);
  EXPECT_EQ(revolution->dropped_points, 0U);
}

}  // namespace
