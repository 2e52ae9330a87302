// SPDX-License-Identifier: Apache-2.0
// The profiles without a public capture (RNG19 single, RNG15 low data rate, FUSA dual; 64 and
// 128 beams; FW 3.x nested metadata) through packets of an independent encoder
// (packet_encoder.hpp), and bad input: metadata that does not fit the packets, truncated and
// other-vendor datagrams, lost packets. Counted, one sentence, never a wrong frame.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ouster_test_support.hpp"
#include "packet_encoder.hpp"
#include "sim/ouster/ouster.hpp"

namespace {

using namespace sim::ouster;
using ouster_test::EncodedPixel;
using ouster_test::Layout;
using ouster_test::PacketSpec;

// Values every field of `layout` can carry, different per pixel and per field.
EncodedPixel pixel_value(Layout layout, unsigned m, unsigned u) {
  // splitmix64: cheap, and different for every pixel and field.
  std::uint64_t state = std::uint64_t{m} * 1000 + u;
  auto random = [&state] {
    state += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return static_cast<std::uint32_t>(z ^ (z >> 31));
  };
  EncodedPixel p;
  const bool rng15 = layout == Layout::rng15 || layout == Layout::fusa_dual;
  const std::uint32_t max_range = layout == Layout::legacy ? 0xfffff : rng15 ? 0x7fff * 8 : 0x7ffff;
  p.range_mm = (random() % (max_range + 1)) & (rng15 ? ~7u : ~0u);
  if ((m + u) % 7 == 0) p.range_mm = 0;  // no return
  p.range2_mm = (random() % (max_range + 1)) & (rng15 ? ~7u : ~0u);
  p.reflectivity = static_cast<std::uint8_t>(random());
  p.reflectivity2 = static_cast<std::uint8_t>(random());
  p.signal = static_cast<std::uint16_t>(random());
  p.signal2 = static_cast<std::uint16_t>(random());
  p.near_ir = static_cast<std::uint16_t>(rng15 ? (random() % 256) * 16 : random() % 65536);
  if (layout == Layout::legacy || layout == Layout::rng19 || rng15) p.signal2 = 0;
  if (layout == Layout::legacy || layout == Layout::rng19 || layout == Layout::rng15) {
    p.range2_mm = 0;
    p.reflectivity2 = 0;
  }
  if (rng15) p.signal = 0;
  return p;
}

struct Case {
  Layout layout;
  unsigned beams;
};

Metadata metadata_for(Layout layout, unsigned beams, unsigned columns = 1024, unsigned per_packet = 16,
                      std::uint32_t init_id = 0x123456) {
  auto m = Metadata::parse(ouster_test::nested_metadata(layout, beams, columns, per_packet, init_id));
  if (!m) throw std::runtime_error(m.error().message);
  return m.value();
}

std::vector<std::vector<std::uint8_t>> rotation(Layout layout, unsigned beams, std::uint32_t frame_id,
                                                unsigned columns = 1024, unsigned per_packet = 16) {
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned first = 0; first < columns; first += per_packet) {
    PacketSpec s;
    s.layout = layout;
    s.beams = beams;
    s.columns_per_packet = per_packet;
    s.frame_id = frame_id;
    s.first_column = static_cast<std::uint16_t>(first);
    s.first_timestamp_ns = 5'000'000'000ULL + frame_id * 100'000'000ULL;
    packets.push_back(ouster_test::encode_packet(s, [&](unsigned m, unsigned u) { return pixel_value(layout, m, u); }));
  }
  return packets;
}

class EveryProfile : public ::testing::TestWithParam<Case> {};

TEST_P(EveryProfile, DecodesEveryFieldTheIndependentEncoderWrote) {
  const auto [layout, beams] = GetParam();
  const Metadata m = metadata_for(layout, beams);
  EXPECT_EQ(to_string(m.format.profile), ouster_test::profile_name(layout));
  for (const auto& payload : rotation(layout, beams, 7)) {
    LidarPacket packet;
    ASSERT_EQ(LidarPacket::parse(payload, m.format, packet, m.init_id), PacketError::none);
    EXPECT_EQ(packet.frame_id(), 7u);
    for (unsigned c = 0; c < packet.columns(); ++c) {
      const Column col = packet.column(c);
      ASSERT_TRUE(col.valid);
      for (unsigned u = 0; u < beams; ++u) {
        const EncodedPixel want = pixel_value(layout, col.measurement_id, u);
        const Pixel got = packet.pixel(c, u);
        ASSERT_EQ(got.range_mm, want.range_mm) << "column " << col.measurement_id << " beam " << u;
        ASSERT_EQ(got.range2_mm, want.range2_mm);
        ASSERT_EQ(got.reflectivity, want.reflectivity);
        ASSERT_EQ(got.reflectivity2, want.reflectivity2);
        ASSERT_EQ(got.signal, want.signal);
        ASSERT_EQ(got.signal2, want.signal2);
        ASSERT_EQ(got.near_ir, want.near_ir);
      }
    }
  }
}

// The channel --intensity asks for, as the encoder wrote it for that return.
std::uint32_t expected_intensity(const EncodedPixel& want, IntensityField field, unsigned ret) {
  switch (field) {
    case IntensityField::signal: return ret == 0 ? want.signal : want.signal2;
    case IntensityField::reflectivity: return ret == 0 ? want.reflectivity : want.reflectivity2;
    default: return want.near_ir;  // one near-IR image, shared by both returns
  }
}

TEST_P(EveryProfile, AWholeRotationBecomesOneFrameWithEveryReturnAtItsRangeAndTheChosenIntensity) {
  const auto [layout, beams] = GetParam();
  const Metadata m = metadata_for(layout, beams);
  for (const IntensityField field : {IntensityField::reflectivity, IntensityField::signal, IntensityField::near_ir}) {
    if (field == IntensityField::signal && !has_signal(m.format.profile)) continue;  // refused, tested below
    SCOPED_TRACE(static_cast<int>(field));
    AssemblerOptions options;
    options.intensity = field;
    auto assembler = FrameAssembler::create(m, options).value();
    std::vector<sim::LidarPoint> points(assembler.max_points());
    assembler.set_output(points);
    std::optional<CompletedFrame> frame;
    for (const auto& payload : rotation(layout, beams, 3)) {
      auto r = assembler.push(payload, 0);
      ASSERT_EQ(r.error, PacketError::none);
      if (r.frame) frame = r.frame;
    }
    ASSERT_TRUE(frame);
    const unsigned returns = returns_of(m.format.profile);
    ASSERT_EQ(frame->point_count, std::size_t{beams} * 1024 * returns);
    EXPECT_EQ(frame->frame_id, 3u);
    for (unsigned ret = 0; ret < returns; ++ret) {
      for (unsigned u = 0; u < beams; ++u) {
        for (unsigned v = 0; v < 1024; v += 37) {
          const auto& p = points[(ret * beams + u) * 1024 + v];  // no pixel shift: staggered = destaggered
          const EncodedPixel want = pixel_value(layout, v, u);
          const std::uint32_t range = ret == 0 ? want.range_mm : want.range2_mm;
          // No beam offset, identity transform: the point lies at its range from the origin.
          ASSERT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), range / 1000.0, 2e-3 + range * 1e-6);
          ASSERT_EQ(p.intensity, expected_intensity(want, field, ret)) << "column " << v << " beam " << u;
          ASSERT_EQ(p.ring, u);
          ASSERT_EQ(p.time_offset_ns, v * 97'656u);
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Profiles, EveryProfile,
    ::testing::Values(Case{Layout::legacy, 64}, Case{Layout::rng19, 32}, Case{Layout::rng19, 128},
                      Case{Layout::rng19_dual, 64}, Case{Layout::rng15, 128}, Case{Layout::fusa_dual, 32}),
    [](const auto& param_info) {
      std::string name = ouster_test::profile_name(param_info.param.layout);
      name += "_";
      name += std::to_string(param_info.param.beams);
      return name;
    });

TEST(OusterMetadata, NestedFirmware3MetadataReadsLikeTheFlatFirmware2One) {
  const Metadata flat = Metadata::load(ouster_test::data_path("OS-1-32-G_v2.1.1_1024x10.json")).value();
  // The same sensor written the FW 3.x way.
  auto json = nlohmann::json::parse(ouster_test::read_text(ouster_test::data_path("OS-1-32-G_v2.1.1_1024x10.json")));
  nlohmann::json nested;
  nested["beam_intrinsics"]["beam_altitude_angles"] = json["beam_altitude_angles"];
  nested["beam_intrinsics"]["beam_azimuth_angles"] = json["beam_azimuth_angles"];
  nested["beam_intrinsics"]["lidar_origin_to_beam_origin_mm"] = json["lidar_origin_to_beam_origin_mm"];
  nested["beam_intrinsics"]["beam_to_lidar_transform"] = {1, 0, 0, json["lidar_origin_to_beam_origin_mm"], 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  nested["lidar_intrinsics"]["lidar_to_sensor_transform"] = json["lidar_to_sensor_transform"];
  nested["imu_intrinsics"]["imu_to_sensor_transform"] = json["imu_to_sensor_transform"];
  nested["lidar_data_format"] = json["data_format"];
  nested["lidar_data_format"]["udp_profile_lidar"] = "LEGACY";
  nested["config_params"]["lidar_mode"] = json["lidar_mode"];
  nested["sensor_info"]["prod_line"] = json["prod_line"];
  nested["sensor_info"]["prod_sn"] = json["prod_sn"];
  nested["sensor_info"]["build_rev"] = json["build_rev"];
  const Metadata m = Metadata::parse(nested.dump()).value();
  EXPECT_EQ(m.describe(), flat.describe());
  EXPECT_EQ(m.format.packet_bytes, flat.format.packet_bytes);
  EXPECT_EQ(m.pixel_shift_by_row, flat.pixel_shift_by_row);
  EXPECT_EQ(m.beam_altitude_deg, flat.beam_altitude_deg);
  EXPECT_EQ(m.lidar_to_sensor, flat.lidar_to_sensor);
  EXPECT_EQ(m.beam_to_lidar, flat.beam_to_lidar);
  EXPECT_EQ(flat.describe(), "OS-1-32-G (sn 992101000280, v2.1.1), LEGACY, 32 beams × 1024 columns at 10 Hz");
}

// FW 1.14 and older name neither lidar_origin_to_beam_origin_mm nor beam_to_lidar_transform:
// ouster-sdk (metadata.cpp, sensor_info.cpp) then takes n by product line, not 0.
TEST(OusterMetadata, MetadataWithoutTheBeamOriginTakesOusterSdksDefaultForItsProductLine) {
  const std::vector<std::pair<std::string, double>> lines{
      {"OS-0-128", 27.67}, {"OS-1-64", 15.806}, {"OS-2-32", 13.762}, {"OS1-64", 12.163}};
  for (const auto& line : lines) {
    auto j = nlohmann::json::parse(ouster_test::nested_metadata(Layout::rng19, 32, 1024, 16, 0x123456));
    j["beam_intrinsics"].erase("lidar_origin_to_beam_origin_mm");
    j["beam_intrinsics"].erase("beam_to_lidar_transform");
    j["sensor_info"]["prod_line"] = line.first;
    auto m = Metadata::parse(j.dump());
    ASSERT_TRUE(m) << m.error().message;
    EXPECT_DOUBLE_EQ(m->lidar_origin_to_beam_origin_mm, line.second) << line.first;
    EXPECT_DOUBLE_EQ(m->beam_to_lidar[3], line.second) << line.first;
  }
}

TEST(OusterMetadata, BrokenMetadataIsRefusedWithOneSentenceNamingTheKey) {
  EXPECT_NE(Metadata::parse("{not json").error().message.find("not valid JSON"), std::string::npos);
  EXPECT_NE(Metadata::parse("{}").error().message.find("data_format"), std::string::npos);
  auto json = nlohmann::json::parse(ouster_test::read_text(ouster_test::data_path("OS-1-32-G_v2.1.1_1024x10.json")));
  auto short_table = json;
  short_table["beam_altitude_angles"].erase(0);
  EXPECT_NE(Metadata::parse(short_table.dump()).error().message.find("beam_altitude_angles"), std::string::npos);
  auto huge = json;
  huge["data_format"]["pixels_per_column"] = 100000;
  EXPECT_FALSE(Metadata::parse(huge.dump()));
  auto profile = json;
  profile["data_format"]["udp_profile_lidar"] = "FIVE_WORD_PIXEL";
  EXPECT_NE(Metadata::parse(profile.dump()).error().message.find("not supported"), std::string::npos);
  auto transform = json;
  transform["lidar_to_sensor_transform"][15] = 2;
  EXPECT_NE(Metadata::parse(transform.dump()).error().message.find("homogeneous"), std::string::npos);
  auto nan = json;
  nan["beam_azimuth_angles"][3] = "x";
  EXPECT_FALSE(Metadata::parse(nan.dump()));
  // Refused when read, not later by the decoder (found by fuzz_ouster_metadata): every metadata
  // that parses makes a frame assembler.
  auto wide = json;
  wide["data_format"]["columns_per_packet"] = 74;
  EXPECT_EQ(Metadata::parse(wide.dump()).error().message,
            "the metadata's columns_per_packet 74 is more than any Ouster sensor sends (at most 64)");
}

// Feeds packets and returns the frames the assembler published.
std::vector<CompletedFrame> feed(FrameAssembler& assembler, const std::vector<std::vector<std::uint8_t>>& packets,
                                 std::vector<sim::LidarPoint>& points) {
  std::vector<CompletedFrame> frames;
  assembler.set_output(points);
  for (const auto& payload : packets) {
    if (auto r = assembler.push(payload, 0); r.frame) {
      frames.push_back(*r.frame);
      assembler.set_output(points);
    }
  }
  return frames;
}

TEST(OusterBadInput, MetadataOfAnotherProfileOrBeamCountPublishesNothingAndSaysWhichFits) {
  // Dual-return 32-beam packets against LEGACY 32-beam metadata, and against 64-beam metadata.
  const auto packets = rotation(Layout::rng19_dual, 32, 1);
  for (const Metadata& wrong : {metadata_for(Layout::legacy, 32), metadata_for(Layout::rng19_dual, 64)}) {
    auto assembler = FrameAssembler::create(wrong, {}).value();
    std::vector<sim::LidarPoint> points(assembler.max_points());
    EXPECT_TRUE(feed(assembler, packets, points).empty());
    EXPECT_EQ(assembler.counters().malformed, packets.size());
    EXPECT_EQ(assembler.counters().rejected[static_cast<unsigned>(PacketError::wrong_size)], packets.size());
    const std::string sentence = describe_mismatch(assembler.counters().last_rejected_size, wrong.format);
    EXPECT_NE(sentence.find("RNG19_RFL8_SIG16_NIR16_DUAL with 32 beams"), std::string::npos) << sentence;
    EXPECT_EQ(sentence.find('\n'), std::string::npos);
  }
}

TEST(OusterBadInput, MetadataWithFewerColumnsThanThePacketsRefusesTheColumnsBeyondIt) {
  const auto packets = rotation(Layout::rng19, 32, 1, 1024);
  auto assembler = FrameAssembler::create(metadata_for(Layout::rng19, 32, 512), {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 1u) << "columns 0–511 are a whole 512-column frame";
  EXPECT_EQ(assembler.counters().rejected[static_cast<unsigned>(PacketError::bad_measurement_id)], 32u);
}

TEST(OusterBadInput, PacketsOfAnotherInitializationAreRefused) {
  const auto packets = rotation(Layout::rng19, 32, 1);
  auto assembler = FrameAssembler::create(metadata_for(Layout::rng19, 32, 1024, 16, 42), {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  EXPECT_TRUE(feed(assembler, packets, points).empty());
  EXPECT_EQ(assembler.counters().rejected[static_cast<unsigned>(PacketError::init_id_mismatch)], packets.size());
}

TEST(OusterBadInput, TruncatedEmptyOversizedAndOtherVendorDatagramsAreCountedNeverDecoded) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  auto good = rotation(Layout::rng19, 32, 1);
  std::vector<std::vector<std::uint8_t>> bad = {
      {}, std::vector<std::uint8_t>(good[0].begin(), good[0].end() - 1),
      std::vector<std::uint8_t>(1198, 0xEE),  // a Hesai-sized datagram
      std::vector<std::uint8_t>(65507, 0x55), std::vector<std::uint8_t>(48, 0)};
  for (const auto& b : bad) EXPECT_NE(assembler.push(b, 0).error, PacketError::none);
  EXPECT_EQ(assembler.counters().malformed, bad.size());
  EXPECT_EQ(assembler.counters().packets, 0u);
  // A packet whose type is not lidar, and a column index past the frame, in a packet of the right size.
  auto not_lidar = good[0];
  not_lidar[0] = 2;
  EXPECT_EQ(assembler.push(not_lidar, 0).error, PacketError::not_lidar);
  auto bad_column = good[0];
  bad_column[32 + 8] = 0xff;
  bad_column[32 + 9] = 0xff;
  EXPECT_EQ(assembler.push(bad_column, 0).error, PacketError::bad_measurement_id);
}

TEST(OusterFrames, ALostLastPacketEndsTheFrameAtTheNextFramesFirstPacketWhichStartsTheNextFrame) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  auto first = rotation(Layout::rng19, 32, 1);
  first.pop_back();  // the packet with column 1023 never came
  const auto second = rotation(Layout::rng19, 32, 2);
  std::vector<std::vector<std::uint8_t>> packets = first;
  packets.insert(packets.end(), second.begin(), second.end());
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].frame_id, 1u);
  EXPECT_EQ(frames[0].missing_columns, 16u);
  EXPECT_EQ(frames[1].frame_id, 2u);
  EXPECT_EQ(frames[1].missing_columns, 0u) << "the packet that ended frame 1 began frame 2";
  EXPECT_EQ(frames[1].packets, 64u);
  EXPECT_EQ(assembler.counters().lost_packets, 1u);
  // The missing columns of frame 1 hold no return: checked on a frame of its own.
}

TEST(OusterFrames, AColumnWindowThatWrapsThroughColumnZeroIsOneWholeFramePerFrameId) {
  // ouster-sdk's windowed_frame2.pcap: 512 columns, window [370, 85]. The sensor sends each
  // frame_id as columns 0–95 (its end), then 368–511 (its start).
  Metadata m = metadata_for(Layout::rng19, 32, 512);
  m.column_window = {370, 85};
  std::vector<std::vector<std::uint8_t>> packets;
  for (std::uint32_t frame_id = 1; frame_id <= 3; ++frame_id) {
    for (const auto& packet : rotation(Layout::rng19, 32, frame_id, 512)) {
      const unsigned first = packet[32 + 8] | (packet[32 + 9] << 8);  // measurement_id of its first column
      if (first < 96 || first >= 368) packets.push_back(packet);
    }
  }
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 3u) << "one frame per frame_id, each complete at column 511";
  for (std::uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(frames[i].frame_id, i + 1);
    EXPECT_TRUE(frames[i].whole);
    EXPECT_EQ(frames[i].packets, 15u);
    EXPECT_EQ(frames[i].missing_columns, 0u);
  }
  EXPECT_EQ(assembler.counters().lost_packets, 0u);
  EXPECT_EQ(assembler.counters().partial_frames_dropped, 0u);
  // Columns 0–85 are in the (last) frame: beam 0's pixel of column 10 (no pixel shift) has its return.
  ASSERT_NE(pixel_value(Layout::rng19, 10, 0).range_mm, 0u);
  const sim::LidarPoint& p = points[10];
  EXPECT_NE(p.x * p.x + p.y * p.y + p.z * p.z, 0.0F);
}

TEST(OusterFrames, APacketArrivingAfterTheNextFramesFirstPacketIsDroppedAsLateNotMadeAFrame) {
  // The last packet of frame 1 swapped with the first of frame 2 (the review's late_packet.pcap).
  const Metadata m = metadata_for(Layout::rng19, 32);
  std::vector<std::vector<std::uint8_t>> packets;
  for (std::uint32_t frame_id = 1; frame_id <= 3; ++frame_id) {
    const auto r = rotation(Layout::rng19, 32, frame_id);
    packets.insert(packets.end(), r.begin(), r.end());
  }
  std::swap(packets[63], packets[64]);
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].frame_id, 1u);
  EXPECT_EQ(frames[0].missing_columns, 16u) << "its last packet came after frame 2 began";
  EXPECT_EQ(frames[1].frame_id, 2u);
  EXPECT_TRUE(frames[1].whole);
  EXPECT_EQ(frames[1].packets, 64u);
  EXPECT_EQ(frames[1].missing_columns, 0u);
  EXPECT_EQ(frames[2].frame_id, 3u);
  EXPECT_EQ(assembler.counters().late_packets, 1u);
  EXPECT_EQ(assembler.counters().partial_frames_dropped, 0u);
  EXPECT_EQ(assembler.counters().lost_packets, 1u);
}

TEST(OusterFrames, APacketOfAFrameAlreadyPublishedIsDroppedAndAFrameCounterThatRestartsIsFollowed) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  std::vector<std::vector<std::uint8_t>> packets = rotation(Layout::rng19, 32, 1000);
  packets.push_back(packets[10]);  // a straggler of frame 1000, already complete
  for (std::uint32_t frame_id : {1001u, 5u}) {  // 5: the sensor restarted its counter
    const auto r = rotation(Layout::rng19, 32, frame_id);
    packets.insert(packets.end(), r.begin(), r.end());
  }
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[1].frame_id, 1001u);
  EXPECT_EQ(frames[2].frame_id, 5u);
  EXPECT_EQ(assembler.counters().late_packets, 1u);
  EXPECT_EQ(assembler.counters().partial_frames_dropped, 0u);
}

TEST(OusterFrames, ANewSpanMidFrameMakesTheRestAPartialFrameNotLatePackets) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  const auto packets = rotation(Layout::rng19, 32, 1);
  AssemblerOptions options;
  options.emit_partial_frames = true;
  auto assembler = FrameAssembler::create(m, options).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  assembler.set_output(points);
  for (std::size_t i = 0; i < 10; ++i) EXPECT_FALSE(assembler.push(packets[i], 0).frame);
  assembler.set_output(points);  // the points so far went elsewhere
  std::optional<CompletedFrame> frame;
  for (std::size_t i = 10; i < packets.size(); ++i) frame = assembler.push(packets[i], 0).frame;
  ASSERT_TRUE(frame);
  EXPECT_FALSE(frame->whole);
  EXPECT_EQ(frame->packets, 54u);
  EXPECT_EQ(assembler.counters().late_packets, 0u);
}

TEST(OusterFrames, AFrameJoinedMidRotationIsDroppedUnlessPartialFramesAreAsked) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  auto packets = rotation(Layout::rng19, 32, 1);
  packets.erase(packets.begin(), packets.begin() + 10);
  for (bool partial : {false, true}) {
    AssemblerOptions options;
    options.emit_partial_frames = partial;
    auto assembler = FrameAssembler::create(m, options).value();
    std::vector<sim::LidarPoint> points(assembler.max_points());
    const auto frames = feed(assembler, packets, points);
    ASSERT_EQ(frames.size(), partial ? 1u : 0u);
    if (partial) {
      EXPECT_FALSE(frames[0].whole);
      // Columns 0–159 never came: no return there.
      EXPECT_EQ(points[5].x, 0.0F);
      EXPECT_EQ(points[5].time_offset_ns, 0u);
    } else {
      EXPECT_EQ(assembler.counters().partial_frames_dropped, 1u);
    }
  }
}

TEST(OusterFrames, ColumnsMissingFromAReusedSpanHoldNoReturnInEitherReturnsImage) {
  // The span still holds the previous frame's points (a SIM loan is reused): the columns of a
  // lost packet must be overwritten, not left over.
  const Metadata m = metadata_for(Layout::rng19_dual, 32);
  auto second = rotation(Layout::rng19_dual, 32, 2);
  second.erase(second.begin() + 10);  // columns 160–175
  std::vector<std::vector<std::uint8_t>> packets = rotation(Layout::rng19_dual, 32, 1);
  packets.insert(packets.end(), second.begin(), second.end());
  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto frames = feed(assembler, packets, points);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[1].missing_columns, 16u);
  for (unsigned ret = 0; ret < 2; ++ret) {
    for (unsigned u = 0; u < 32; ++u) {
      for (unsigned v : {159u, 160u, 175u, 176u}) {
        const auto& p = points[(ret * 32 + u) * 1024 + v];  // no pixel shift
        const bool lost = v >= 160 && v <= 175;
        const EncodedPixel want = pixel_value(Layout::rng19_dual, v, u);
        const std::uint32_t range = ret == 0 ? want.range_mm : want.range2_mm;
        EXPECT_EQ(p.ring, u);
        EXPECT_EQ(p.return_index, ret);
        if (lost || range == 0) {
          EXPECT_EQ(p.x, 0.0F) << "column " << v << " beam " << u << " return " << ret;
          EXPECT_EQ(p.y, 0.0F);
          EXPECT_EQ(p.z, 0.0F);
        } else {
          EXPECT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), range / 1000.0, 2e-3 + range * 1e-6);
        }
        if (lost) {
          EXPECT_EQ(p.intensity, 0.0F);
          EXPECT_EQ(p.time_offset_ns, 0u);
        } else {
          EXPECT_EQ(p.intensity, ret == 0 ? want.signal : want.signal2);
          EXPECT_EQ(p.time_offset_ns, v * 97'656u);
        }
      }
    }
  }
}

// The sensor's clock is unsigned 64-bit. Stamps beyond the signed range (corrupt, or a clock
// set wrong) once overflowed the subtraction that gives a column its time after the frame's stamp.
TEST(OusterFrames, ColumnTimesAreRightAcrossTheSignedLimitAndClampedWhenAStampGoesBackOrFarAhead) {
  const Metadata m = metadata_for(Layout::rng19, 32);
  constexpr std::uint64_t kPeriod = 97'656;
  auto packet = [](const PacketSpec& s) {
    return ouster_test::encode_packet(s, [](unsigned v, unsigned u) { return pixel_value(Layout::rng19, v, u); });
  };
  auto frame_starting_at = [&packet](std::uint32_t frame_id, std::uint64_t first) {
    std::vector<std::vector<std::uint8_t>> packets;
    for (unsigned c = 0; c < 1024; c += 16) {
      PacketSpec s;
      s.layout = Layout::rng19;
      s.frame_id = frame_id;
      s.first_column = static_cast<std::uint16_t>(c);
      s.first_timestamp_ns = first;
      packets.push_back(packet(s));
    }
    return packets;
  };
  constexpr std::uint64_t kNearTheLimit = (std::uint64_t{1} << 63) - 100 * kPeriod;  // column 100 crosses it
  auto second = frame_starting_at(2, 1'000'000'000);
  PacketSpec back;  // columns 80–95 stamped before the frame's first column
  back.frame_id = 2;
  back.first_column = 80;
  back.first_timestamp_ns = 0;
  second[5] = packet(back);
  PacketSpec ahead = back;  // columns 96–111 at the end of the clock
  ahead.first_column = 96;
  ahead.first_timestamp_ns = std::numeric_limits<std::uint64_t>::max() - 1024 * kPeriod;
  second[6] = packet(ahead);

  auto assembler = FrameAssembler::create(m, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  const auto first_frame = feed(assembler, frame_starting_at(1, kNearTheLimit), points);
  ASSERT_EQ(first_frame.size(), 1u);
  EXPECT_EQ(static_cast<std::uint64_t>(first_frame[0].stamp_ns), kNearTheLimit);
  for (unsigned v = 0; v < 1024; ++v) ASSERT_EQ(points[v].time_offset_ns, v * kPeriod) << "column " << v;
  ASSERT_EQ(feed(assembler, second, points).size(), 1u);
  for (unsigned v = 0; v < 1024; ++v) {
    const std::uint64_t want = v >= 80 && v < 96    ? 0
                               : v >= 96 && v < 112 ? std::numeric_limits<std::uint32_t>::max()
                                                    : v * kPeriod;
    ASSERT_EQ(points[v].time_offset_ns, want) << "column " << v;
  }
}

TEST(OusterFrames, ASpanSmallerThanAFrameGetsItsFirstPointsAndTheRestAreCountedAsDropped) {
  const Metadata m = metadata_for(Layout::rng19_dual, 32);
  const auto packets = rotation(Layout::rng19_dual, 32, 1);
  std::size_t returns = 0;  // what a dense frame holds
  for (unsigned v = 0; v < 1024; ++v) {
    for (unsigned u = 0; u < 32; ++u) {
      const EncodedPixel p = pixel_value(Layout::rng19_dual, v, u);
      returns += (p.range_mm != 0) + (p.range2_mm != 0);
    }
  }
  for (CloudLayout layout : {CloudLayout::organized, CloudLayout::dense}) {
    AssemblerOptions options;
    options.layout = layout;
    auto assembler = FrameAssembler::create(m, options).value();
    const std::size_t room = 1000;
    sim::LidarPoint guard{};
    guard.ring = 0xBEEF;
    std::vector<sim::LidarPoint> points(assembler.max_points(), guard);
    assembler.set_output(std::span<sim::LidarPoint>(points).first(room));
    std::optional<CompletedFrame> frame;
    for (const auto& payload : packets) {
      if (auto r = assembler.push(payload, 0); r.frame) frame = r.frame;
    }
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->point_count, room);
    const std::size_t made = layout == CloudLayout::organized ? assembler.max_points() : returns;
    EXPECT_EQ(assembler.counters().dropped_points, made - room);
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(points[i].ring == 0xBEEF, i >= room) << "point " << i << " of a span of " << room;
    }
  }
}

// The decoder works on four columns at a time; a packet of two columns (or one with invalid
// columns) leaves a group part-filled. Every pixel must still land at its own destaggered place
// with its own values, in both layouts, and nothing else may be written.
TEST(OusterFrames, PacketsOfTwoColumnsPutEveryPixelAtItsPlaceInBothLayouts) {
  const unsigned beams = 32, columns = 1024;
  Metadata m = metadata_for(Layout::rng19_dual, beams, columns, 2);
  for (unsigned u = 0; u < beams; ++u) m.pixel_shift_by_row[u] = static_cast<int>(u % 3) * 5;  // wraps at the row's end
  const auto packets = rotation(Layout::rng19_dual, beams, 4, columns, 2);
  auto expect_point = [&](const sim::LidarPoint& p, unsigned u, unsigned v, unsigned ret) {
    const EncodedPixel want = pixel_value(Layout::rng19_dual, v, u);
    const std::uint32_t range = ret == 0 ? want.range_mm : want.range2_mm;
    EXPECT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), range / 1000.0, 2e-3 + range * 1e-6)
        << "beam " << u << " column " << v << " return " << ret;
    EXPECT_EQ(p.intensity, ret == 0 ? want.reflectivity : want.reflectivity2);
    EXPECT_EQ(p.ring, u);
    EXPECT_EQ(p.return_index, ret);
    EXPECT_EQ(p.time_offset_ns, v * 97'656u);
  };
  for (CloudLayout layout : {CloudLayout::organized, CloudLayout::dense}) {
    AssemblerOptions options;
    options.layout = layout;
    options.intensity = IntensityField::reflectivity;
    auto assembler = FrameAssembler::create(m, options).value();
    // One point more than a frame, marked: whatever the decoder does not write keeps the mark.
    sim::LidarPoint mark{};
    mark.x = 12345.0f;
    std::vector<sim::LidarPoint> points(assembler.max_points() + 1, mark);
    assembler.set_output(points);
    std::optional<CompletedFrame> frame;
    for (const auto& payload : packets) {
      if (auto r = assembler.push(payload, 0); r.frame) frame = r.frame;
    }
    ASSERT_TRUE(frame);
    if (layout == CloudLayout::organized) {
      ASSERT_EQ(frame->point_count, std::size_t{beams} * columns * 2);
      EXPECT_EQ(points.back().x, mark.x) << "a point was written beyond the frame";
      for (unsigned ret = 0; ret < 2; ++ret) {
        for (unsigned u = 0; u < beams; ++u) {
          for (unsigned v = 0; v < columns; ++v) {
            const unsigned destaggered = (v + m.pixel_shift_by_row[u]) % columns;
            expect_point(points[(ret * beams + u) * columns + destaggered], u, v, ret);
          }
        }
      }
    } else {
      // Packet order: packet by packet, beam by beam, column by column, first then second return.
      std::size_t at = 0;
      for (unsigned first = 0; first < columns; first += 2) {
        for (unsigned u = 0; u < beams; ++u) {
          for (unsigned v = first; v < first + 2; ++v) {
            const EncodedPixel want = pixel_value(Layout::rng19_dual, v, u);
            for (unsigned ret = 0; ret < 2; ++ret) {
              if ((ret == 0 ? want.range_mm : want.range2_mm) == 0) continue;
              ASSERT_LT(at, frame->point_count);
              expect_point(points[at++], u, v, ret);
            }
          }
        }
      }
      EXPECT_EQ(frame->point_count, at);
    }
  }
}

TEST(OusterFrames, TheFusaHeaderCarriesA32BitFrameId) {
  const Metadata m = metadata_for(Layout::fusa_dual, 32);
  PacketSpec s;
  s.layout = Layout::fusa_dual;
  s.frame_id = 0x12345678;
  const auto payload = ouster_test::encode_packet(s, [](unsigned, unsigned) { return EncodedPixel{}; });
  LidarPacket packet;
  ASSERT_EQ(LidarPacket::parse(payload, m.format, packet, m.init_id), PacketError::none);
  EXPECT_EQ(packet.frame_id(), 0x12345678u);
  EXPECT_EQ(packet.serial(), 992100000001u);
}

TEST(OusterFrames, AskingForSignalFromAProfileWithoutItIsRefusedWithOneSentence) {
  AssemblerOptions options;
  options.intensity = IntensityField::signal;
  auto created = FrameAssembler::create(metadata_for(Layout::rng15, 32), options);
  ASSERT_FALSE(created);
  EXPECT_NE(created.error().message.find("no signal"), std::string::npos);
}

TEST(OusterFrames, OusterPacketsAreRecognisedWithoutMetadataAndOthersAreNot) {
  for (Layout l : {Layout::legacy, Layout::rng19, Layout::rng19_dual, Layout::rng15, Layout::fusa_dual}) {
    const auto packets = rotation(l, 64, 1);
    EXPECT_TRUE(guess_format(packets[3])) << ouster_test::profile_name(l);
  }
  EXPECT_FALSE(guess_format(std::vector<std::uint8_t>(1198, 0xEE)));
  EXPECT_FALSE(guess_format(std::vector<std::uint8_t>(6464, 0xFF)));
}

}  // namespace
