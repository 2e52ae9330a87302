// SPDX-License-Identifier: Apache-2.0
// Packet validation and field decoding: real packets checked against values worked out by
// hand from the reference notes, synthetic XT16/QT64 packets built from the layout tables,
// and every way a packet can be cut short or carry impossible values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "../../../drivers/hesai/src/crc32_mpeg2.hpp"
#include "packet_builder.hpp"
#include "hesai_test_data.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;
using hesai_test::data_path;

namespace {

// CRC-32/MPEG-2 one bit at a time, straight from its definition: the yardstick for both fast ways.
std::uint32_t crc_bit_by_bit(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFF'FFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= std::uint32_t{p[i]} << 24;
    for (int bit = 0; bit < 8; ++bit) c = (c & 0x8000'0000u) ? (c << 1) ^ 0x04C1'1DB7u : c << 1;
  }
  return c;
}

// The QT128's checks run through carry-less multiplication on x86-64 and through tables on
// aarch64: both must be the CRC on every length and alignment, not only on the real capture.
TEST(HesaiCrc, BothWaysAreTheStandardCrcOnEveryLengthAndAlignment) {
  const std::string check = "123456789";  // the catalogue's check value for CRC-32/MPEG-2
  const auto* digits = reinterpret_cast<const std::uint8_t*>(check.data());
  EXPECT_EQ(detail::crc32_mpeg2(digits, check.size()), 0x0376'E6E7u);
  EXPECT_EQ(detail::crc32_mpeg2_portable(digits, check.size()), 0x0376'E6E7u);

  std::mt19937 random(1071);
  std::vector<std::uint8_t> bytes(1100);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(random());
  for (std::size_t offset = 0; offset < 4; ++offset) {
    for (std::size_t n = 0; n + offset <= bytes.size(); n += n < 200 ? 1 : 13) {
      const std::uint8_t* p = bytes.data() + offset;
      const std::uint32_t expected = crc_bit_by_bit(p, n);
      ASSERT_EQ(detail::crc32_mpeg2(p, n), expected) << n << " bytes at offset " << offset;
      ASSERT_EQ(detail::crc32_mpeg2_portable(p, n), expected) << n << " bytes at offset " << offset;
    }
  }
  // The body's own length, on both ways.
  EXPECT_EQ(detail::crc32_mpeg2(bytes.data(), 1028), crc_bit_by_bit(bytes.data(), 1028));
  if (!detail::crc32_mpeg2_folds()) std::printf("note: this CPU has no carry-less multiply\n");
}

std::vector<std::uint8_t> first_payload(const char* file) {
  auto packets = hesai_test::read_udp_payloads(data_path(file));
  EXPECT_FALSE(packets.empty());
  return packets.empty() ? std::vector<std::uint8_t>{} : packets.front().bytes;
}

PacketError parse(const std::vector<std::uint8_t>& bytes, Model model) {
  Packet packet;
  return Packet::parse(bytes, model, packet);
}

constexpr std::int64_t s_to_ns = 1'000'000'000;

// A synthetic XT32M packet (6 blocks of 32 channels) with `returns` returns per firing.
std::vector<std::uint8_t> xt32m_packet(unsigned returns) {
  hesai_test::SyntheticPacket s;
  s.channels = 32;
  s.blocks = 6;
  s.returns = returns;
  s.return_mode = returns == 3 ? 0x3d : returns == 2 ? 0x3b : 0x33;
  return hesai_test::build_xt(s);
}

}  // namespace

TEST(HesaiModel, NamesParseAndCapacityCoversARevolution) {
  for (Model m : all_models) EXPECT_EQ(parse_model(to_string(m)), m);
  EXPECT_EQ(parse_model("pandar64"), Model::pandar64);
  EXPECT_EQ(parse_model("XT32"), Model::pandar_xt32);
  EXPECT_EQ(parse_model("qt64"), Model::pandar_qt64);
  EXPECT_FALSE(parse_model("Pandar128"));
  EXPECT_FALSE(parse_model(""));
  // Pandar64 dual at 10 Hz: 1800 firings × 64 channels × 2 returns, plus margin.
  EXPECT_GE(frame_capacity(Model::pandar64, 2, 600), 1800u * 64 * 2);
  EXPECT_LT(frame_capacity(Model::pandar64, 2, 600), 1800u * 64 * 2 * 12 / 10 + 400);
  // Lower rpm means more firings per revolution.
  EXPECT_GT(frame_capacity(Model::pandar40p, 1, 300), frame_capacity(Model::pandar40p, 1, 600));
  EXPECT_EQ(frame_capacity(Model::pandar40p, 1, 1200, 0.0), 900u * 40 + 400);
}

TEST(HesaiPacket, Pandar64FirstPacketOfTheCaptureByHand) {
  const auto bytes = first_payload("pandar64_dual.pcap");
  ASSERT_EQ(bytes.size(), 1198u);
  EXPECT_EQ(detect_model(bytes), Model::pandar64);
  Packet p;
  ASSERT_EQ(Packet::parse(bytes, Model::pandar64, p), PacketError::none);
  EXPECT_EQ(p.channels(), 64u);
  EXPECT_EQ(p.blocks(), 6u);
  EXPECT_EQ(p.return_mode(), ReturnMode::dual_last_strongest);
  EXPECT_EQ(p.returns(), 2u);
  EXPECT_FLOAT_EQ(p.distance_unit_m(), 0.004f);
  EXPECT_EQ(p.motor_rpm(), 599);
  EXPECT_EQ(p.sequence(), 2339721u);
  // UTC bytes 78 06 19 0c 02 09: 1900+120 = 2020-06-25 12:02:09, plus 977341 µs.
  EXPECT_EQ(p.time_ns(), 1593086529 * s_to_ns + 977341000);
  EXPECT_EQ(p.azimuth(0), 71);
  EXPECT_EQ(p.azimuth(1), 71);  // a dual-return pair shares its azimuth
  EXPECT_EQ(p.raw_distance(0, 0), 173);
  EXPECT_EQ(p.raw_distance(0, 19), 539);
  EXPECT_EQ(p.raw_distance(1, 19), 112);
  // Firing times (reference §2): block 0 of a dual packet is group k = (6-0-1)/2 = 2:
  // -42580 - 2·55560 = -153700 ns, channel 0 adds -23180 ns.
  EXPECT_EQ(p.block_offset_ns(0), -153700);
  EXPECT_EQ(p.firing_offset_ns(0, 0), -176880);
  EXPECT_EQ(p.firing_offset_ns(5, 50), -42580 - 3620);
}

TEST(HesaiPacket, Pandar64PointsOfTheFirstFiringByHand) {
  const auto bytes = first_payload("pandar64_dual.pcap");
  auto cal = Calibration::load(data_path("pandar64.calibration.csv"), Model::pandar64);
  ASSERT_TRUE(cal);
  AssemblerOptions options;
  options.model = Model::pandar64;
  options.cut_by = CutBy::block_azimuth;  // keep every channel of the packet in one frame
  options.emit_partial_frames = true;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler);
  std::vector<sim::LidarPoint> points(2000);
  assembler->set_output(points);
  ASSERT_EQ(assembler->push(bytes, 0).error, PacketError::none);
  const auto frame = assembler->finish();
  ASSERT_TRUE(frame);
  EXPECT_FALSE(frame->whole);
  ASSERT_GT(frame->point_count, 20u);
  // Channel 1 (ring 0): both returns are raw 173, reflectivity 0, so only the last (the
  // Strongest block, return_index 1) is kept. d = 0.692 m, az = 0.71 - 1.042°, el = 14.9°:
  // x = d·cos(el)·sin(az) = -0.003875, y = 0.668721, z = d·sin(el) = 0.177936.
  EXPECT_EQ(points[0].ring, 0);
  EXPECT_EQ(points[0].return_index, 1);
  EXPECT_NEAR(points[0].x, -0.003875, 1e-6);
  EXPECT_NEAR(points[0].y, 0.668721, 1e-6);
  EXPECT_NEAR(points[0].z, 0.177936, 1e-6);
  EXPECT_EQ(points[0].intensity, 0.0f);
  // Channel 20 (ring 19): Last 539 (2.156 m) and Strongest 112 (0.448 m) are far apart: both.
  std::vector<sim::LidarPoint> ring19;
  for (std::size_t i = 0; i < frame->point_count; ++i) {
    if (points[i].ring == 19 && std::abs(points[i].y) < 3) ring19.push_back(points[i]);
    if (ring19.size() == 2) break;
  }
  ASSERT_EQ(ring19.size(), 2u);
  EXPECT_EQ(ring19[0].return_index, 0);
  EXPECT_NEAR(ring19[0].x, 0.144198, 1e-6);
  EXPECT_NEAR(ring19[0].y, 2.151139, 1e-6);
  EXPECT_NEAR(ring19[0].z, -0.012004, 1e-6);
  EXPECT_EQ(ring19[1].return_index, 1);
  EXPECT_NEAR(ring19[1].y, 0.446990, 1e-6);
  // The frame's stamp is the earliest firing of its first group: packet time + block 0's
  // offset + the earliest channel (-54668 ns, channels 12 and 40).
  EXPECT_EQ(frame->stamp_ns, 1593086529 * s_to_ns + 977341000 - 153700 - 54668);
  // Ring 0 fired 54668 - 23180 ns after the earliest channel.
  EXPECT_EQ(points[0].time_offset_ns, 54668u - 23180u);
}

TEST(HesaiPacket, PandarXT32AndPandar40PHeadersByHand) {
  const auto xt = first_payload("pandarxt32_dual.pcap");
  ASSERT_EQ(xt.size(), 1080u);
  EXPECT_EQ(detect_model(xt), Model::pandar_xt32);
  Packet p;
  ASSERT_EQ(Packet::parse(xt, Model::pandar_xt32, p), PacketError::none);
  EXPECT_EQ(p.channels(), 32u);
  EXPECT_EQ(p.blocks(), 8u);
  EXPECT_EQ(p.returns(), 2u);
  EXPECT_TRUE(p.sequence().has_value());
  EXPECT_GE(p.motor_rpm(), 599);
  EXPECT_LE(p.motor_rpm(), 600);
  // Year byte 119 counts from 1900 (reference §4): 2019.
  EXPECT_GE(p.time_ns(), 1546300800 * s_to_ns);  // 2019-01-01
  EXPECT_LT(p.time_ns(), 1577836800 * s_to_ns);  // 2020-01-01
  // XT32 timing: 5632 - 50000·((8-b-1)/2) + 368 + 1512·ch ns.
  EXPECT_EQ(p.firing_offset_ns(0, 0), 5632 - 150000 + 368);
  EXPECT_EQ(p.firing_offset_ns(7, 31), 5632 + 368 + 1512 * 31);

  const auto p40 = first_payload("pandar40p_single_packet_raw.pcapng");
  ASSERT_EQ(p40.size(), 1266u);
  EXPECT_EQ(detect_model(p40), Model::pandar40p);
  ASSERT_EQ(Packet::parse(p40, Model::pandar40p, p), PacketError::none);
  EXPECT_EQ(p.return_mode(), ReturnMode::last);
  EXPECT_EQ(p.returns(), 1u);
  EXPECT_EQ(p.motor_rpm(), 599);
  EXPECT_EQ(p.sequence(), 270964u);
  EXPECT_EQ(p.azimuth(0), 11666);
  // Year byte 17 counts from 2000 on the Pandar40P (reference §3): 2017.
  EXPECT_GE(p.time_ns(), 1483228800 * s_to_ns);  // 2017-01-01
  EXPECT_LT(p.time_ns(), 1514764800 * s_to_ns);  // 2018-01-01
  // 40P timing, single return: -28580 - 55560·(10-0-1) + channel 0's -42220 ns.
  EXPECT_EQ(p.firing_offset_ns(0, 0), -28580 - 55560 * 9 - 42220);
}

TEST(HesaiPacket, SyntheticXT16AndQT64FromTheLayoutTables) {
  hesai_test::SyntheticPacket s;
  s.channels = 16;
  const auto xt16 = hesai_test::build_xt(s);
  ASSERT_EQ(xt16.size(), 568u);
  EXPECT_EQ(detect_model(xt16), Model::pandar_xt16);
  Packet p;
  ASSERT_EQ(Packet::parse(xt16, Model::pandar_xt16, p), PacketError::none);
  EXPECT_EQ(p.time_ns(), 1551675967 * s_to_ns + 250000000);  // 2019-03-04 05:06:07.25
  EXPECT_EQ(p.raw_distance(3, 15), 16 * 250);
  EXPECT_EQ(p.reflectivity(3, 15), 15);
  EXPECT_EQ(p.firing_offset_ns(0, 3), -350000 + 6000 + 3024 * 3);  // XT16: 3.024 µs per channel
  // Year byte 0: bytes 2..5 are big-endian Unix seconds (SDK 2, reference §4).
  s.utc = {0, 0, 0x5C, 0x7C, 0xB1, 0x3F};
  ASSERT_EQ(Packet::parse(hesai_test::build_xt(s), Model::pandar_xt16, p), PacketError::none);
  EXPECT_EQ(p.time_ns(), std::int64_t{0x5C7CB13F} * s_to_ns + 250000000);

  hesai_test::SyntheticPacket q;
  q.returns = 1;
  q.first_azimuth = 1000;
  q.azimuth_step = 60;
  q.utc = {124, 2, 29, 0, 0, 0};  // a leap day: 2024-02-29
  q.distance = [](unsigned, unsigned ch) { return static_cast<std::uint16_t>(ch == 5 ? 2500 : 0); };
  const auto qt = hesai_test::build_qt64(q);
  ASSERT_EQ(qt.size(), 1072u);
  EXPECT_EQ(detect_model(qt), Model::pandar_qt64);
  ASSERT_EQ(Packet::parse(qt, Model::pandar_qt64, p), PacketError::none);
  EXPECT_EQ(p.time_ns(), 1709164800 * s_to_ns + 250000000);
  // QT64 fires after the timestamp: 25710 + 500000·1/3 ns for block 1, channel 56 = 129.6 µs
  // (not nebula's 12.96 µs typo).
  EXPECT_EQ(p.firing_offset_ns(1, 55), 25710 + 166666 + 129600);

  // One point by hand: el 10°, azimuth offset 2°, block azimuth 10°, 2500 × 4 mm = 10 m:
  // x = 10·cos10°·sin12° = 2.047530, y = 9.632873, z = 10·sin10° = 1.736482.
  std::vector<ChannelAngles> angles(64, ChannelAngles{0.0f, 0.0f});
  angles[5] = {10.0f, 2.0f};
  auto cal = Calibration::from_angles(angles);
  ASSERT_TRUE(cal);
  AssemblerOptions options;
  options.model = Model::pandar_qt64;
  options.emit_partial_frames = true;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler) << assembler.error().message;
  std::vector<sim::LidarPoint> points(300);
  assembler->set_output(points);
  ASSERT_EQ(assembler->push(qt, 7).error, PacketError::none);
  const auto frame = assembler->finish();
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->point_count, 4u);  // one point per block
  EXPECT_EQ(frame->host_receive_ns, 7);
  EXPECT_NEAR(points[0].x, 2.047530, 1e-5);
  EXPECT_NEAR(points[0].y, 9.632873, 1e-5);
  EXPECT_NEAR(points[0].z, 1.736482, 1e-5);
  EXPECT_EQ(points[0].ring, 5);
  // Point times: block b fires 166666·b ns after block 0 (same channel).
  EXPECT_EQ(points[1].time_offset_ns - points[0].time_offset_ns, 166666u);
}

TEST(HesaiPacket, EveryTruncationIsRejectedWithoutReadingPastTheEnd) {
  hesai_test::SyntheticPacket s16;
  s16.channels = 16;
  hesai_test::SyntheticPacket s32;
  s32.channels = 32;
  const std::vector<std::pair<Model, std::vector<std::uint8_t>>> packets{
      {Model::pandar64, first_payload("pandar64_dual.pcap")},
      {Model::pandar_xt32, first_payload("pandarxt32_dual.pcap")},
      {Model::pandar40p, first_payload("pandar40p_last_20hz_raw.pcapng")},
      {Model::pandar_xt16, hesai_test::build_xt(s16)},
      {Model::pandar_qt64, hesai_test::build_qt64(hesai_test::SyntheticPacket{})},
      {Model::pandar_qt128, first_payload("pandarqt128_dual.pcap")},
      {Model::pandar_xt32m, xt32m_packet(3)},
  };
  for (const auto& [model, full] : packets) {
    ASSERT_EQ(parse(full, model), PacketError::none) << to_string(model);
    for (std::size_t n = 0; n < full.size(); ++n) {
      // An exact-size heap copy, so a read past the end is caught by AddressSanitizer.
      const std::vector<std::uint8_t> cut(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
      const PacketError e = parse(cut, model);
      if (n == info(model).payload_size && info(model).has_optional_trailer()) {
        // Without its optional trailer (UDP sequence, QT128 signature) the packet is the
        // model's other valid size.
        EXPECT_EQ(e, PacketError::none) << to_string(model);
        continue;
      }
      EXPECT_NE(e, PacketError::none) << to_string(model) << " cut to " << n << " bytes";
      if (detect_model(cut) != model) {
        EXPECT_TRUE(e == PacketError::too_short || e == PacketError::bad_size ||
                    e == PacketError::wrong_model)
            << to_string(model) << " cut to " << n << ": " << to_string(e);
      }
    }
    // One byte too many is no packet of the model either.
    auto longer = full;
    longer.push_back(0);
    EXPECT_NE(parse(longer, model), PacketError::none);
  }
}

TEST(HesaiPacket, ImpossibleFieldValuesAreRejectedWithTheirReason) {
  const auto good = first_payload("pandar64_dual.pcap");
  auto with = [&](std::size_t at, std::uint8_t value) {
    auto p = good;
    p[at] = value;
    return parse(p, Model::pandar64);
  };
  constexpr std::size_t tail = 1172;
  EXPECT_EQ(with(0, 0x00), PacketError::bad_marker);
  EXPECT_EQ(with(2, 40), PacketError::bad_header);           // laser count
  EXPECT_EQ(with(3, 7), PacketError::bad_header);            // block count
  EXPECT_EQ(with(5, 0), PacketError::bad_distance_unit);
  EXPECT_EQ(with(tail + 14, 0x00), PacketError::bad_return_mode);
  // Triple return would make blocks 0-2 one group, but block 2 has the next azimuth.
  EXPECT_EQ(with(tail + 14, 0x3d), PacketError::bad_azimuth);
  EXPECT_EQ(with(tail + 17, 13), PacketError::bad_time);     // month 13
  EXPECT_EQ(with(tail + 18, 0), PacketError::bad_time);      // day 0
  EXPECT_EQ(with(tail + 19, 24), PacketError::bad_time);     // hour 24
  EXPECT_EQ(with(tail + 13, 0xFF), PacketError::bad_time);   // µs field ≥ 1 000 000
  {
    auto p = good;  // no date yet (month and day 0): read as 1970-01-01 12:02:09.977341
    p[tail + 16] = 0;
    p[tail + 17] = 0;
    p[tail + 18] = 0;
    Packet packet;
    ASSERT_EQ(Packet::parse(p, Model::pandar64, packet), PacketError::none);
    EXPECT_EQ(packet.time_ns(), (12 * 3600 + 2 * 60 + 9) * s_to_ns + 977341000);
  }
  {
    auto p = good;  // 2020-02-30
    p[tail + 17] = 2;
    p[tail + 18] = 30;
    EXPECT_EQ(parse(p, Model::pandar64), PacketError::bad_time);
  }
  {
    auto p = good;  // azimuth 360.00°
    hesai_test::put16(p, 8, 36000);
    hesai_test::put16(p, 8 + 194, 36000);
    EXPECT_EQ(parse(p, Model::pandar64), PacketError::bad_azimuth);
  }
  {
    auto p = good;  // the two blocks of a dual-return pair disagree
    hesai_test::put16(p, 8 + 194, 500);
    EXPECT_EQ(parse(p, Model::pandar64), PacketError::bad_azimuth);
  }
  {
    auto p = good;  // the third group goes backwards
    hesai_test::put16(p, 8 + 4 * 194, 10);
    hesai_test::put16(p, 8 + 5 * 194, 10);
    EXPECT_EQ(parse(p, Model::pandar64), PacketError::bad_azimuth);
  }
  // Another model's well-formed packet is "wrong model", not "malformed".
  EXPECT_EQ(parse(first_payload("pandarxt32_dual.pcap"), Model::pandar64),
            PacketError::wrong_model);
  EXPECT_EQ(parse(good, Model::pandar40p), PacketError::wrong_model);
  // Pandar40P: every block carries its own start marker; triple return cannot divide 10 blocks.
  auto p40 = first_payload("pandar40p_last_20hz_raw.pcapng");
  p40[124 * 7 + 1] = 0x00;
  EXPECT_EQ(parse(p40, Model::pandar40p), PacketError::bad_marker);
  p40 = first_payload("pandar40p_last_20hz_raw.pcapng");
  p40[1254] = 0x3d;
  EXPECT_EQ(parse(p40, Model::pandar40p), PacketError::bad_return_mode);
  // XT: another protocol version.
  auto xt = first_payload("pandarxt32_dual.pcap");
  xt[2] = 5;
  EXPECT_EQ(parse(xt, Model::pandar_xt32), PacketError::bad_header);
  // Detection refuses what is no Hesai packet.
  EXPECT_FALSE(detect_model(std::vector<std::uint8_t>(1198, 0)));
  EXPECT_FALSE(detect_model(std::vector<std::uint8_t>(3, 0xEE)));
  EXPECT_FALSE(detect_model({}));
}

TEST(HesaiPacket, RejectedPacketsAreCountedByReasonAndMakeNoFrame) {
  auto cal = Calibration::load(data_path("pandar64.calibration.csv"), Model::pandar64);
  ASSERT_TRUE(cal);
  AssemblerOptions options;
  options.emit_partial_frames = true;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler);
  std::vector<sim::LidarPoint> points(1000);
  assembler->set_output(points);
  const auto good = first_payload("pandar64_dual.pcap");
  for (std::size_t n = 0; n < good.size(); n += 7) {
    const std::vector<std::uint8_t> cut(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    const PushResult r = assembler->push(cut, 0);
    EXPECT_NE(r.error, PacketError::none);
    EXPECT_FALSE(r.frame);
  }
  EXPECT_EQ(assembler->push(first_payload("pandarxt32_dual.pcap"), 0).error,
            PacketError::wrong_model);
  const auto& c = assembler->counters();
  EXPECT_EQ(c.packets, 0u);
  EXPECT_EQ(c.wrong_model, 1u);
  EXPECT_EQ(c.malformed, (good.size() + 6) / 7);
  // Every cut is too short, except 1197 bytes: longer than the sequence-less 1194.
  EXPECT_EQ(c.rejected[static_cast<std::size_t>(PacketError::too_short)], c.malformed - 1);
  EXPECT_EQ(c.rejected[static_cast<std::size_t>(PacketError::bad_size)], 1u);
  EXPECT_EQ(assembler->pending_points(), 0u);
  EXPECT_FALSE(assembler->finish());
}

TEST(HesaiPacket, SyntheticXT32MInEveryReturnModeFromTheLayoutTables) {
  for (const unsigned returns : {1u, 2u, 3u}) {
    SCOPED_TRACE("returns " + std::to_string(returns));
    const auto bytes = xt32m_packet(returns);
    ASSERT_EQ(bytes.size(), 820u);
    EXPECT_EQ(detect_model(bytes), Model::pandar_xt32m);
    Packet p;
    ASSERT_EQ(Packet::parse(bytes, Model::pandar_xt32m, p), PacketError::none);
    EXPECT_EQ(p.blocks(), 6u);
    EXPECT_EQ(p.channels(), 32u);
    EXPECT_EQ(p.returns(), returns);
    EXPECT_EQ(p.sequence(), 1u);
    EXPECT_EQ(p.time_ns(), 1551675967 * s_to_ns + 250000000);
    EXPECT_EQ(p.raw_distance(5, 31), 32 * 250);
    // The last firing group is at the packet time; earlier groups 50 µs apart before it.
    // Channels c and c + 16 fire together, 2.888 µs apart from c to c + 1 (nebula).
    const unsigned groups = 6 / returns;
    EXPECT_EQ(p.firing_offset_ns(0, 0), -50000 * static_cast<int>(groups - 1) + 6000);
    EXPECT_EQ(p.firing_offset_ns(5, 2), 6000 + 2 * 2888);
    EXPECT_EQ(p.firing_offset_ns(5, 18), p.firing_offset_ns(5, 2));
    // Blocks of one return group fire together.
    EXPECT_EQ(p.block_offset_ns(0), p.block_offset_ns(returns - 1));
  }
  // XT32 packets are not XT32M packets and the other way round.
  EXPECT_EQ(parse(xt32m_packet(1), Model::pandar_xt32), PacketError::wrong_model);
  EXPECT_EQ(parse(first_payload("pandarxt32_dual.pcap"), Model::pandar_xt32m),
            PacketError::wrong_model);
}

TEST(HesaiPacket, PandarQT128FirstPacketOfTheCaptureByHand) {
  const auto bytes = first_payload("pandarqt128_dual.pcap");
  ASSERT_EQ(bytes.size(), 1127u);  // with the 32-byte signature area
  Packet p;
  ASSERT_EQ(Packet::parse(bytes, Model::pandar_qt128, p), PacketError::none);
  EXPECT_EQ(p.channels(), 128u);
  EXPECT_EQ(p.blocks(), 2u);
  EXPECT_EQ(p.return_mode(), ReturnMode::dual_last_strongest);
  EXPECT_FLOAT_EQ(p.distance_unit_m(), 0.004f);
  EXPECT_EQ(p.motor_rpm(), 600);
  // Tail bytes 78 0a 09 0c 03 1d, µs 4b 26 06 00: 2020-10-09 12:03:29.403019 UTC.
  EXPECT_EQ(p.time_ns(), 1602245009 * s_to_ns + 403019000);
  EXPECT_EQ(p.sequence(), 0x006192CDu);
  EXPECT_EQ(p.azimuth(0), 1080);
  EXPECT_EQ(p.azimuth(1), 1080);
  // Mode flag 0: this dual-return firing is the second loop (channels 32–63 dark).
  EXPECT_EQ(p.firing_loop(0), 1u);
  EXPECT_EQ(p.firing_offset_ns(0, 0), 9000 + 2312);
  EXPECT_EQ(p.firing_offset_ns(1, 127), 9000 + 48976);
  // The short form without the signature is the same packet.
  const std::vector<std::uint8_t> short_form(bytes.begin(), bytes.begin() + 1095);
  EXPECT_EQ(detect_model(short_form), Model::pandar_qt128);
  ASSERT_EQ(Packet::parse(short_form, Model::pandar_qt128, p), PacketError::none);
}

TEST(HesaiPacket, PandarQT128SingleReturnAlternatesFiringLoopsWithinAPacket) {
  hesai_test::SyntheticPacket s;
  s.returns = 1;
  s.return_mode = 0x37;
  s.first_azimuth = 100;
  s.azimuth_step = 40;
  s.signature = false;
  const auto bytes = hesai_test::build_qt128(s);
  ASSERT_EQ(bytes.size(), 1095u);
  Packet p;
  ASSERT_EQ(Packet::parse(bytes, Model::pandar_qt128, p), PacketError::none);
  EXPECT_EQ(p.firing_loop(0), 0u);
  EXPECT_EQ(p.firing_loop(1), 1u);
  EXPECT_EQ(p.azimuth(1), 140);
  // Block 1 fires one 0.4° step (111.11 µs at 600 rpm) after block 0; channel 32 is the
  // first loop's 27.656 µs, channel 0 the second loop's 2.312 µs.
  EXPECT_EQ(p.firing_offset_ns(0, 32), 9000 + 27656);
  EXPECT_EQ(p.firing_offset_ns(1, 0), 9000 + 111110 + 2312);
  EXPECT_EQ(p.raw_distance(0, 0), 0);   // dark in the first loop
  EXPECT_NE(p.raw_distance(1, 0), 0);
}

TEST(HesaiPacket, PandarQT128WithABadCrcIsDroppedAndCounted) {
  const auto good = first_payload("pandarqt128_dual.pcap");
  ASSERT_EQ(parse(good, Model::pandar_qt128), PacketError::none);
  // One flipped bit in a distance, in the functional-safety state, in the motor speed, and in
  // each CRC itself.
  for (const std::size_t at : {std::size_t{500}, std::size_t{1045}, std::size_t{1075},
                               std::size_t{1041}, std::size_t{1058}, std::size_t{1093}}) {
    auto bad = good;
    bad[at] ^= 0x10;
    EXPECT_EQ(parse(bad, Model::pandar_qt128), PacketError::bad_crc) << "byte " << at;
  }
  // The signature area is not covered: a changed signature byte still decodes.
  auto signed_differently = good;
  signed_differently[1100] ^= 0xFF;
  EXPECT_EQ(parse(signed_differently, Model::pandar_qt128), PacketError::none);

  auto cal = Calibration::load(data_path("pandarqt128.calibration.csv"), Model::pandar_qt128);
  ASSERT_TRUE(cal) << cal.error().message;
  AssemblerOptions options;
  options.model = Model::pandar_qt128;
  options.emit_partial_frames = true;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler) << assembler.error().message;
  std::vector<sim::LidarPoint> points(frame_capacity(Model::pandar_qt128, 2));
  assembler->set_output(points);
  auto corrupted = good;
  corrupted[600] ^= 0x01;
  const PushResult r = assembler->push(corrupted, 0);
  EXPECT_EQ(r.error, PacketError::bad_crc);
  EXPECT_EQ(assembler->counters().crc_errors, 1u);
  EXPECT_EQ(assembler->counters().malformed, 0u);
  EXPECT_EQ(assembler->counters().rejected[static_cast<std::size_t>(PacketError::bad_crc)], 1u);
  EXPECT_EQ(assembler->counters().packets, 0u);
  EXPECT_EQ(assembler->pending_points(), 0u);  // nothing of it was decoded
  EXPECT_EQ(assembler->push(good, 0).error, PacketError::none);
  EXPECT_GT(assembler->pending_points(), 0u);
}

TEST(HesaiAssemblerQT128, FaultStateAndMotorSpeedReachTheFrame) {
  // Three turns of synthetic QT128 packets at 598, 599, 600 rpm; in the second, one packet
  // reports "output untrusted" with fault code 0x0123, the rest "normal".
  std::vector<ChannelAngles> angles(128, ChannelAngles{0.0f, 0.0f});
  auto cal = Calibration::from_angles(angles);
  ASSERT_TRUE(cal);
  AssemblerOptions options;
  options.model = Model::pandar_qt128;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler) << assembler.error().message;
  std::vector<sim::LidarPoint> points(frame_capacity(Model::pandar_qt128, 2));
  assembler->set_output(points);
  std::vector<CompletedFrame> frames;
  constexpr unsigned per_turn = 900;  // dual return: one 0.4° firing per packet
  for (unsigned k = 0; k < 3 * per_turn + 10; ++k) {
    hesai_test::SyntheticPacket s;
    s.returns = 2;
    s.return_mode = 0x39;
    s.first_azimuth = static_cast<std::uint16_t>((k * 40) % 36000);
    s.azimuth_step = 40;
    s.mode_flag = static_cast<std::uint8_t>(k % 2);
    s.rpm = static_cast<std::uint16_t>(598 + k / per_turn);
    s.sequence = k;
    s.micros = k * 111;
    s.distance = [](unsigned, unsigned ch) { return static_cast<std::uint16_t>((ch % 40 + 1) * 250); };
    if (k == per_turn + 450) s.safety = {0x88, 0x21, 0x23, 0x01};  // state 4, current fault
    const PushResult r = assembler->push(hesai_test::build_qt128(s), 0);
    ASSERT_EQ(r.error, PacketError::none) << to_string(r.error);
    if (r.frame) {
      frames.push_back(*r.frame);
      assembler->set_output(points);
    }
  }
  ASSERT_EQ(frames.size(), 2u);  // turns 1 and 2 (turn 0, where the assembler joined, is not whole)
  for (const auto& f : frames) {
    ASSERT_TRUE(f.safety.has_value());
    // 96 lasers fire per firing, 900 firings, identical dual returns keep one.
    EXPECT_EQ(f.point_count, 900u * 96);
  }
  EXPECT_EQ(frames[0].motor_rpm, 599);
  EXPECT_EQ(frames[0].safety->state, LidarState::output_untrusted);
  EXPECT_EQ(frames[0].safety->fault_type, FaultCodeType::current);
  EXPECT_EQ(frames[0].safety->fault_code, 0x0123);
  EXPECT_EQ(frames[0].safety->total_fault_codes, 2);
  EXPECT_EQ(frames[0].safety->fault_code_id, 1);
  EXPECT_EQ(frames[1].motor_rpm, 600);
  EXPECT_EQ(frames[1].safety->state, LidarState::normal);
  // The latest packet's state, for status lines.
  ASSERT_TRUE(assembler->functional_safety().has_value());
  EXPECT_EQ(assembler->functional_safety()->state, LidarState::normal);
  EXPECT_EQ(assembler->motor_rpm(), 601);  // the first packets of turn 3
  // A firing-time file cannot describe the two loops: refused with a sentence.
  auto firetimes = FiretimeCorrection::parse("Channel,fire time(us)\n" + [] {
    std::string rows;
    for (int c = 1; c <= 128; ++c) rows += std::to_string(c) + ",1.0\n";
    return rows;
  }(), Model::pandar_qt128);
  ASSERT_TRUE(firetimes) << firetimes.error().message;
  options.firetimes = *firetimes;
  const auto refused = FrameAssembler::create(*cal, options);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("--firetimes"), std::string::npos);
}
