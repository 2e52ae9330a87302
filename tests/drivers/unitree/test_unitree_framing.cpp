// SPDX-License-Identifier: Apache-2.0
// Framing layers against packets built by the test encoder from the reference notes: datagrams
// merged and split, streams cut at every offset, CRC failures, truncation, foreign packets.
#include <gtest/gtest.h>

#include <cstring>
#include <string_view>

#include "sim/unitree/crc.hpp"
#include "sim/unitree/framing.hpp"
#include "unitree_encoder.hpp"

namespace {

using namespace unitree_test;
using sim::unitree::L2Framer;
using sim::unitree::MavlinkFramer;

std::span<const std::uint8_t> as_bytes(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

L2PointSpec point_spec(std::uint32_t seq) {
  L2PointSpec s;
  s.seq = seq;
  s.stamp_sec = 1000;
  for (std::size_t j = 0; j < 300; ++j) {
    s.ranges[j] = static_cast<std::uint16_t>(1000 + j);
    s.intensities[j] = static_cast<std::uint8_t>(j);
  }
  return s;
}

// Feeds `bytes` in the given chunks and returns the sizes and types of the packets that came out.
struct L2Out {
  std::vector<std::pair<std::uint32_t, std::size_t>> packets;  // (type, size)
};
void drain(L2Framer& framer, L2Out& out) {
  while (auto p = framer.next()) {
    std::uint32_t type = 0;
    std::memcpy(&type, p->data() + 4, 4);
    out.packets.emplace_back(type, p->size());
  }
}
void feed_all(L2Framer& framer, std::span<const std::uint8_t> bytes, L2Out& out) {
  while (!bytes.empty()) {
    bytes = bytes.subspan(framer.feed(bytes));
    drain(framer, out);
  }
}

TEST(UnitreeCrc, KnownCheckValues) {
  // The catalogue check values of both CRCs over "123456789".
  EXPECT_EQ(sim::unitree::crc32(as_bytes("123456789")), 0xCBF43926U);
  EXPECT_EQ(reference_crc32(as_bytes("123456789")), 0xCBF43926U);
  sim::unitree::Crc16Mcrf4xx crc;
  crc.add(as_bytes("123456789"));
  EXPECT_EQ(crc.value(), 0x6F91);
}

TEST(UnitreeL2Framer, OnePacketPerDatagram) {
  L2Framer framer;
  L2Out out;
  const Bytes packet = l2_point_packet(point_spec(1));
  ASSERT_EQ(packet.size(), 1044U);
  feed_all(framer, packet, out);
  ASSERT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(out.packets[0], (std::pair<std::uint32_t, std::size_t>{102, 1044}));
  EXPECT_EQ(framer.counters().packets, 1U);
  EXPECT_EQ(framer.counters().resyncs, 0U);
}

TEST(UnitreeL2Framer, SeveralPacketsInOneDatagram) {
  L2Framer framer;
  L2Out out;
  const Bytes datagram = concat({l2_point_packet(point_spec(1)), l2_imu_packet({}),
                                 l2_point_packet(point_spec(2))});
  feed_all(framer, datagram, out);
  ASSERT_EQ(out.packets.size(), 3U);
  EXPECT_EQ(out.packets[1], (std::pair<std::uint32_t, std::size_t>{104, 80}));
  EXPECT_EQ(framer.counters().skipped_bytes, 0U);
}

TEST(UnitreeL2Framer, OnePacketOverFourDatagrams) {
  L2Framer framer;
  L2Out out;
  const Bytes packet = l2_point_packet(point_spec(1));
  const std::span<const std::uint8_t> all(packet);
  feed_all(framer, all.subspan(0, 300), out);
  feed_all(framer, all.subspan(300, 300), out);
  feed_all(framer, all.subspan(600, 300), out);
  EXPECT_TRUE(out.packets.empty());
  feed_all(framer, all.subspan(900), out);
  EXPECT_EQ(out.packets.size(), 1U);
}

TEST(UnitreeL2Framer, LargePacketOfUnknownTypeSpansDatagrams) {
  // A 2D packet (5536 B) arrives in 4 datagrams; its tail need not be 00 FF.
  Bytes packet = l2_packet(103, Bytes(5512, std::uint8_t{0x42}));
  packet[packet.size() - 1] = std::uint8_t{0x00};
  L2Framer framer;
  L2Out out;
  const std::span<const std::uint8_t> all(packet);
  for (std::size_t off = 0; off < all.size(); off += 1400) {
    feed_all(framer, all.subspan(off, std::min<std::size_t>(1400, all.size() - off)), out);
  }
  ASSERT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(out.packets[0].second, 5536U);
}

TEST(UnitreeL2Framer, StreamCutAtEveryOffset) {
  const Bytes stream = concat({l2_point_packet(point_spec(1)), l2_imu_packet({}),
                               l2_point_packet(point_spec(2))});
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    L2Framer framer;
    L2Out out;
    const std::span<const std::uint8_t> all(stream);
    feed_all(framer, all.first(cut), out);
    feed_all(framer, all.subspan(cut), out);
    ASSERT_EQ(out.packets.size(), 3U) << "cut at " << cut;
    ASSERT_EQ(framer.counters().skipped_bytes, 0U) << "cut at " << cut;
  }
}

TEST(UnitreeL2Framer, ByteByByte) {
  const Bytes stream = concat({l2_imu_packet({}), l2_point_packet(point_spec(1))});
  L2Framer framer;
  L2Out out;
  for (std::size_t i = 0; i < stream.size(); ++i) {
    feed_all(framer, std::span<const std::uint8_t>(stream).subspan(i, 1), out);
  }
  EXPECT_EQ(out.packets.size(), 2U);
}

TEST(UnitreeL2Framer, BadCrcIsCountedAndDropped) {
  Bytes bad = l2_point_packet(point_spec(1));
  bad[500] ^= std::uint8_t{0x01};
  const Bytes stream = concat({bad, l2_point_packet(point_spec(2))});
  L2Framer framer;
  L2Out out;
  feed_all(framer, stream, out);
  EXPECT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(framer.counters().bad_crc, 1U);
  EXPECT_EQ(framer.counters().truncated, 0U);
}

TEST(UnitreeL2Framer, CrcOverHeaderAndDataIsRejected) {
  // The official header comment says "crc check of head and data"; the verified receivers check
  // the data only. A packet following the comment must fail.
  Bytes packet = l2_imu_packet({});
  const std::uint32_t wrong =
      reference_crc32(std::span<const std::uint8_t>(packet).first(packet.size() - 12));
  std::memcpy(packet.data() + packet.size() - 12, &wrong, 4);
  L2Framer framer;
  L2Out out;
  feed_all(framer, packet, out);
  EXPECT_TRUE(out.packets.empty());
  EXPECT_EQ(framer.counters().bad_crc, 1U);
}

TEST(UnitreeL2Framer, OfficialCommentSizesAreRejected) {
  // A 3D point packet claiming the official comment's 1036 B is not a real L2 packet.
  Bytes packet = l2_packet(102, Bytes(1012, std::uint8_t{0}));
  ASSERT_EQ(packet.size(), 1036U);
  L2Framer framer;
  L2Out out;
  feed_all(framer, concat({packet, l2_imu_packet({})}), out);
  ASSERT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(out.packets[0].first, 104U);
  EXPECT_EQ(framer.counters().wrong_header, 1U);
}

TEST(UnitreeL2Framer, TruncatedPacketFollowedByGoodOnes) {
  const Bytes first = l2_point_packet(point_spec(1));
  const Bytes stream = concat({std::span<const std::uint8_t>(first).first(600), l2_imu_packet({}),
                               l2_point_packet(point_spec(2)), l2_imu_packet({})});
  L2Framer framer;
  L2Out out;
  feed_all(framer, stream, out);
  ASSERT_EQ(out.packets.size(), 3U);
  EXPECT_EQ(framer.counters().truncated, 1U);
  EXPECT_EQ(framer.counters().bad_crc, 0U);
}

TEST(UnitreeL2Framer, TruncatedAtEndOfInput) {
  const Bytes packet = l2_point_packet(point_spec(1));
  L2Framer framer;
  L2Out out;
  feed_all(framer, std::span<const std::uint8_t>(packet).first(700), out);
  framer.finish();
  EXPECT_TRUE(out.packets.empty());
  EXPECT_EQ(framer.counters().truncated, 1U);
}

TEST(UnitreeL2Framer, WrongMagicIsSkipped) {
  Bytes wrong = l2_point_packet(point_spec(1));
  wrong[3] = std::uint8_t{0x0B};
  L2Framer framer;
  L2Out out;
  feed_all(framer, concat({wrong, l2_imu_packet({})}), out);
  ASSERT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(out.packets[0].first, 104U);
  EXPECT_EQ(framer.counters().skipped_bytes, wrong.size());
  EXPECT_EQ(framer.counters().resyncs, 1U);
}

TEST(UnitreeL2Framer, RoboSensePacketIsRejected) {
  L2Framer framer;
  L2Out out;
  feed_all(framer, robosense_packet(), out);
  feed_all(framer, l2_point_packet(point_spec(1)), out);
  ASSERT_EQ(out.packets.size(), 1U);
  EXPECT_EQ(out.packets[0].first, 102U);
  EXPECT_EQ(framer.counters().foreign, 1U);
  EXPECT_EQ(framer.counters().packets, 1U);
}

TEST(UnitreeL2Framer, GarbageBetweenPacketsResyncs) {
  const Bytes garbage = {std::uint8_t{0x55}, std::uint8_t{0xAA}, std::uint8_t{0x05}, std::uint8_t{0x00},
                         std::uint8_t{0x12}, std::uint8_t{0x55}};
  L2Framer framer;
  L2Out out;
  feed_all(framer, concat({garbage, l2_imu_packet({}), garbage, l2_imu_packet({})}), out);
  EXPECT_EQ(out.packets.size(), 2U);
  EXPECT_EQ(framer.counters().skipped_bytes, 2 * garbage.size());
  EXPECT_EQ(framer.counters().resyncs, 2U);
}

TEST(UnitreeL2Framer, HugeDatagramIsTakenInPieces) {
  // More bytes than the bounded buffer holds: feed() takes what fits and nothing is lost.
  Bytes stream;
  for (std::uint32_t i = 0; i < 40; ++i) {
    const Bytes p = l2_point_packet(point_spec(i));
    stream.insert(stream.end(), p.begin(), p.end());
  }
  L2Framer framer;
  L2Out out;
  feed_all(framer, stream, out);
  EXPECT_EQ(out.packets.size(), 40U);
}

// ---- MAVLink ---------------------------------------------------------------------------------

std::array<std::uint16_t, 120> ranges_with_zero_tail() {
  std::array<std::uint16_t, 120> r{};
  for (std::size_t j = 0; j < 60; ++j) r[j] = static_cast<std::uint16_t>(500 + j);
  return r;  // the last 60 are zero: a sender trims them off
}


struct MavOut {
  std::vector<std::uint32_t> ids;
  std::vector<Bytes> payloads;
};
void feed_all(MavlinkFramer& framer, std::span<const std::uint8_t> bytes, MavOut& out) {
  while (!bytes.empty()) {
    bytes = bytes.subspan(framer.feed(bytes));
    while (auto m = framer.next()) {
      out.ids.push_back(m->msgid);
      out.payloads.emplace_back(m->payload.begin(), m->payload.end());
    }
  }
}

TEST(UnitreeMavlinkFramer, TrimmedPayloadIsZeroExtended) {
  const auto ranges = ranges_with_zero_tail();
  const Bytes frame = l1_distance_frame(7, ranges);
  ASSERT_EQ(frame.size(), 10U + 126U + 2U);  // 6 B of ids + 60 ranges, the zeros trimmed
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, frame, out);
  ASSERT_EQ(out.ids.size(), 1U);
  EXPECT_EQ(out.ids[0], 16U);
  EXPECT_EQ(out.payloads[0], l1_distance_payload(7, ranges));
}

TEST(UnitreeMavlinkFramer, UntrimmedAndSignedFramesAreAccepted) {
  const Bytes payload = l1_distance_payload(3, ranges_with_zero_tail());
  MavlinkSpec untrimmed{16, 74};
  untrimmed.trim = false;
  MavlinkSpec signed_frame{16, 74};
  signed_frame.signed_frame = true;
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, concat({mavlink_frame(untrimmed, payload), mavlink_frame(signed_frame, payload)}),
           out);
  ASSERT_EQ(out.ids.size(), 2U);
  EXPECT_EQ(out.payloads[0], payload);
  EXPECT_EQ(out.payloads[1], payload);
}

TEST(UnitreeMavlinkFramer, WrongCrcExtraIsRejected) {
  const Bytes payload = l1_imu_payload({0, 0, 0, 1}, {1, 2, 3}, {4, 5, 6}, 9);
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, mavlink_frame({19, 0}, payload), out);  // CRC_EXTRA left out
  feed_all(framer, mavlink_frame({19, 110}, payload), out);
  ASSERT_EQ(out.ids.size(), 1U);
  EXPECT_EQ(framer.counters().bad_crc, 1U);
}

TEST(UnitreeMavlinkFramer, UnknownMessageIsSkipped) {
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, concat({mavlink_frame({250, 1}, Bytes(8, std::uint8_t{1})),
                           l1_imu_frame({0, 0, 0, 1}, {}, {}, 1)}),
           out);
  ASSERT_EQ(out.ids.size(), 1U);
  EXPECT_EQ(out.ids[0], 19U);
  EXPECT_GE(framer.counters().unknown, 1U);
}

Bytes l1_stream() {
  L1AuxSpec aux;
  aux.packet_id = 7;
  aux.reflect.fill(0);
  aux.sys_vertical_angle_span = 0.5F;
  return concat({l1_distance_frame(7, ranges_with_zero_tail(), 0), l1_auxiliary_frame(aux, 1),
                 l1_imu_frame({0, 0, 0, 1}, {0.1F, 0, 0}, {0, 0, 9.8F}, 7, 2),
                 l1_distance_frame(8, ranges_with_zero_tail(), 3)});
}

TEST(UnitreeMavlinkFramer, SerialStreamCutAtEveryOffset) {
  const Bytes stream = l1_stream();
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    MavlinkFramer framer;
    MavOut out;
    const std::span<const std::uint8_t> all(stream);
    feed_all(framer, all.first(cut), out);
    feed_all(framer, all.subspan(cut), out);
    ASSERT_EQ(out.ids, (std::vector<std::uint32_t>{16, 17, 19, 16})) << "cut at " << cut;
    ASSERT_EQ(framer.counters().skipped_bytes, 0U) << "cut at " << cut;
  }
}

TEST(UnitreeMavlinkFramer, GarbageAndStxBytesBetweenFrames) {
  const Bytes noise = {std::uint8_t{0xFD}, std::uint8_t{0x00}, std::uint8_t{0xFD}, std::uint8_t{0x10},
                       std::uint8_t{0x02}, std::uint8_t{0xFD}, std::uint8_t{0x33}};
  const Bytes frames = l1_stream();
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, concat({noise, frames, noise}), out);
  EXPECT_EQ(out.ids, (std::vector<std::uint32_t>{16, 17, 19, 16}));
  framer.finish();
  EXPECT_GT(framer.counters().skipped_bytes, 0U);
}

TEST(UnitreeMavlinkFramer, TruncatedFrameThenGoodOnes) {
  const Bytes cut = l1_distance_frame(5, ranges_with_zero_tail());
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, concat({std::span<const std::uint8_t>(cut).first(40), l1_stream()}), out);
  EXPECT_EQ(out.ids, (std::vector<std::uint32_t>{16, 17, 19, 16}));
  EXPECT_EQ(framer.counters().truncated, 1U);
}

TEST(UnitreeMavlinkFramer, TruncatedAtEndOfInput) {
  const Bytes frame = l1_imu_frame({0, 0, 0, 1}, {}, {}, 1);
  MavlinkFramer framer;
  MavOut out;
  feed_all(framer, std::span<const std::uint8_t>(frame).first(frame.size() - 1), out);
  framer.finish();
  EXPECT_TRUE(out.ids.empty());
  EXPECT_EQ(framer.counters().truncated, 1U);
}

}  // namespace
