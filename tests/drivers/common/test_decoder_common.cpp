// SPDX-License-Identifier: Apache-2.0
// What the family decoders share (drivers/common/decoder): FrameOutput, the output span and
// carry-over of the assemblers that cut revolutions (Hesai, Velodyne), on made-up points whose
// ring says which frame and which point they are; and the little-endian readers on known bytes.
#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/lidar/frame_output.hpp"
#include "sim/lidar/little_endian.hpp"

namespace {

using sim::LidarPoint;
using sim::lidar::FrameOutput;

// A point named by its ring: 1xx for the frame in progress, 2xx for the next one.
LidarPoint named(std::uint16_t name) {
  LidarPoint p{};
  p.ring = name;
  return p;
}

void put_current(FrameOutput& out, std::uint16_t name) {
  LidarPoint* slot = out.take_current();
  ASSERT_NE(slot, nullptr);
  *slot = named(name);
}

void put_next(FrameOutput& out, std::uint16_t name) {
  LidarPoint* slot = out.take_carry();
  ASSERT_NE(slot, nullptr);
  *slot = named(name);
}

std::vector<std::uint16_t> names(std::span<const LidarPoint> points) {
  std::vector<std::uint16_t> out;
  for (const LidarPoint& p : points) out.push_back(p.ring);
  return out;
}

using Names = std::vector<std::uint16_t>;

TEST(FrameOutput, replacing_the_span_mid_frame_keeps_the_next_frames_points_out_of_the_frame_in_progress) {
  FrameOutput out;
  out.reserve_carry(16);
  std::array<LidarPoint, 8> a{}, b{}, c{};
  out.attach(a);
  put_current(out, 101);
  put_current(out, 102);
  put_current(out, 103);
  put_next(out, 201);  // near the cut: the next revolution's first points
  put_next(out, 202);

  // The span is replaced while the frame is in progress: its three points stay in `a`, lost to
  // it, and the new span starts empty. The next frame's points must not become its front (as
  // Velodyne's assembler did: the next revolution inside this one, and missing from the next).
  const FrameOutput::Attached replaced = out.attach(b);
  EXPECT_EQ(replaced.lost, 3u);
  EXPECT_EQ(replaced.did_not_fit, 0u);
  EXPECT_EQ(out.output_count(), 0u);
  EXPECT_EQ(out.pending(), 0u);
  put_current(out, 104);
  EXPECT_EQ(names(std::span(b).first(out.output_count())), (Names{104}));

  // The frame is handed out; the next span begins with the next frame's carried points.
  out.hand_out();
  EXPECT_EQ(out.pending(), 2u);
  const FrameOutput::Attached next = out.attach(c);
  EXPECT_EQ(next.lost, 0u);
  EXPECT_EQ(next.did_not_fit, 0u);
  EXPECT_EQ(names(std::span(c).first(out.output_count())), (Names{201, 202}));
}

TEST(FrameOutput, without_a_span_the_frame_in_progress_waits_in_the_carry_over_and_leads_the_next_span) {
  FrameOutput out;
  out.reserve_carry(4);
  EXPECT_FALSE(out.attached());
  put_current(out, 101);  // no span yet: the carry-over is the frame in progress's storage
  put_current(out, 102);
  EXPECT_EQ(out.pending(), 2u);
  EXPECT_EQ(out.next().capacity, 0u);  // no room for a next frame until a span comes
  std::array<LidarPoint, 4> span{};
  out.attach(span);
  put_current(out, 103);
  EXPECT_EQ(names(std::span(span).first(out.output_count())), (Names{101, 102, 103}));
}

TEST(FrameOutput, a_carry_over_larger_than_the_new_span_says_how_many_points_did_not_fit) {
  FrameOutput out;
  out.reserve_carry(4);
  for (std::uint16_t i = 0; i < 4; ++i) put_current(out, static_cast<std::uint16_t>(101 + i));
  EXPECT_EQ(out.take_current(), nullptr);  // the carry-over is full
  std::array<LidarPoint, 3> span{};
  const FrameOutput::Attached attached = out.attach(span);
  EXPECT_EQ(attached.did_not_fit, 1u);
  EXPECT_EQ(attached.lost, 0u);
  EXPECT_EQ(names(std::span(span).first(out.output_count())), (Names{101, 102, 103}));
  EXPECT_EQ(out.take_current(), nullptr);  // the span is full
}

TEST(FrameOutput, a_frame_not_handed_out_gives_its_span_to_the_next_frame) {
  FrameOutput out;
  out.reserve_carry(4);
  std::array<LidarPoint, 4> span{};
  out.attach(span);
  put_current(out, 101);
  put_current(out, 102);
  put_next(out, 201);
  const FrameOutput::Advanced advanced = out.advance();  // e.g. a partial frame dropped
  EXPECT_EQ(advanced.discarded, 2u);
  EXPECT_EQ(advanced.did_not_fit, 0u);
  EXPECT_TRUE(out.attached());
  EXPECT_EQ(names(std::span(span).first(out.output_count())), (Names{201}));
}

TEST(FrameOutput, a_frame_not_handed_out_without_a_span_is_discarded_from_the_carry_over) {
  FrameOutput out;
  out.reserve_carry(4);
  put_current(out, 101);
  const FrameOutput::Advanced advanced = out.advance();
  EXPECT_EQ(advanced.discarded, 1u);
  EXPECT_EQ(out.pending(), 0u);
  std::array<LidarPoint, 4> span{};
  out.attach(span);
  EXPECT_EQ(out.output_count(), 0u);  // nothing of the discarded frame leads the next span
}

TEST(FrameOutput, finishing_early_drops_only_the_next_frames_points) {
  FrameOutput out;
  out.reserve_carry(4);
  std::array<LidarPoint, 4> span{};
  out.attach(span);
  put_current(out, 101);
  put_next(out, 201);
  put_next(out, 202);
  EXPECT_EQ(out.drop_next(), 2u);
  EXPECT_EQ(out.output_count(), 1u);
  out.hand_out();
  EXPECT_EQ(out.pending(), 0u);
  // Without a span the carry-over is the frame in progress: nothing of it is the next frame's.
  put_current(out, 301);
  EXPECT_EQ(out.drop_next(), 0u);
  EXPECT_EQ(out.pending(), 1u);
}

TEST(FrameOutput, a_packets_trailing_points_move_to_the_next_frame_in_order) {
  FrameOutput out;
  out.reserve_carry(2);
  std::array<LidarPoint, 8> span{};
  out.attach(span);
  for (std::uint16_t i = 0; i < 5; ++i) put_current(out, static_cast<std::uint16_t>(101 + i));
  EXPECT_TRUE(out.move_tail_to_carry(3).empty());  // no room for three: nothing moves
  EXPECT_EQ(out.output_count(), 5u);
  const std::span<LidarPoint> moved = out.move_tail_to_carry(2);
  EXPECT_EQ(names(moved), (Names{104, 105}));
  EXPECT_EQ(out.output_count(), 3u);
  out.hand_out();
  std::array<LidarPoint, 8> next{};
  out.attach(next);
  EXPECT_EQ(names(std::span(next).first(out.output_count())), (Names{104, 105}));
}

TEST(FrameOutput, a_block_written_in_place_extends_the_frame_by_what_it_kept) {
  FrameOutput out;
  out.reserve_carry(2);
  EXPECT_EQ(out.output_room(), 0u);  // no span: no room, so no in-place write
  std::array<LidarPoint, 8> span{};
  out.attach(span);
  put_current(out, 101);
  EXPECT_EQ(out.output_room(), 7u);
  LidarPoint* end = out.output_end();
  end[0] = named(102);
  end[1] = named(103);
  out.extend(2);
  EXPECT_EQ(names(std::span(span).first(out.output_count())), (Names{101, 102, 103}));
}

TEST(LittleEndian, reads_each_field_in_wire_order_at_any_alignment) {
  const std::array<std::uint8_t, 10> bytes{0xff, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0xff};
  EXPECT_EQ(sim::lidar::le16(bytes.data() + 1), 0x0201u);
  EXPECT_EQ(sim::lidar::le_uint(bytes.data() + 1, 3), 0x030201u);
  EXPECT_EQ(sim::lidar::le_uint(bytes.data() + 1, 5), 0x0504030201u);
  EXPECT_EQ(sim::lidar::le32(bytes.data() + 1), 0x04030201u);
  EXPECT_EQ(sim::lidar::le64(bytes.data() + 1), 0x0807060504030201u);
  const std::array<std::uint8_t, 5> one{0x00, 0x00, 0x00, 0x80, 0x3f};  // 1.0f after one byte
  EXPECT_EQ(sim::lidar::le_f32(one.data() + 1), 1.0f);
  EXPECT_EQ(sim::lidar::le32(bytes.data() + 6), 0xff080706u);
}

}  // namespace
