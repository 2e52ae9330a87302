// SPDX-License-Identifier: Apache-2.0
// Decoding and scan assembly: XYZ against values worked out by hand from the formulas in the
// reference notes (§7.2 and §8), scan boundaries, time offsets, storage bounds, IMU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "sim/unitree/decoder.hpp"
#include "sim/unitree/l2_protocol.hpp"
#include "unitree_encoder.hpp"
#include "vector_sink.hpp"

namespace {

using namespace unitree_test;
using sim::unitree::Decoder;
using sim::unitree::DecoderOptions;
using sim::unitree::Model;
using sim::unitree::TimeSource;

constexpr float kTol = 1e-4F;

// One packet with a single non-zero range at index `j`, decoded through the whole Decoder.
std::vector<sim::LidarPoint> decode_one(const L2PointSpec& spec) {
  DecoderOptions options;
  options.packets_per_scan = 1;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  decoder.push(l2_point_packet(spec), 0);
  EXPECT_EQ(sink.scans.size(), 1U);
  return sink.scans.empty() ? std::vector<sim::LidarPoint>{} : sink.scans[0].points;
}

TEST(UnitreeL2Xyz, StraightAheadWithAxisOffsets) {
  // α = θ = β = ξ = 0, r = 2 m: A = b_axis, B = r, C = 0 → (b, r, a).
  L2PointSpec s;
  s.a_axis_dist = 0.05F;
  s.b_axis_dist = 0.01F;
  s.ranges[0] = 2000;
  s.intensities[0] = 77;
  const auto points = decode_one(s);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, 0.01F, kTol);
  EXPECT_NEAR(points[0].y, 2.0F, kTol);
  EXPECT_NEAR(points[0].z, 0.05F, kTol);
  EXPECT_EQ(points[0].intensity, 77.0F);
}

TEST(UnitreeL2Xyz, HorizontalQuarterTurn) {
  // θ = 90°: x = −B = −r, y = A = b_axis.
  L2PointSpec s;
  s.b_axis_dist = 0.01F;
  s.com_horizontal_angle_start = static_cast<float>(std::numbers::pi / 2);
  s.ranges[0] = 2000;
  const auto points = decode_one(s);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, -2.0F, kTol);
  EXPECT_NEAR(points[0].y, 0.01F, kTol);
  EXPECT_NEAR(points[0].z, 0.0F, kTol);
}

TEST(UnitreeL2Xyz, MirrorAngleThirtyDegrees) {
  // α = 30°, r = 2: B = cos30°·2 = 1.7320508, C = sin30°·2 = 1.0.
  L2PointSpec s;
  s.angle_min = static_cast<float>(std::numbers::pi / 6);
  s.ranges[0] = 2000;
  const auto points = decode_one(s);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, 0.0F, kTol);
  EXPECT_NEAR(points[0].y, 1.7320508F, kTol);
  EXPECT_NEAR(points[0].z, 1.0F, kTol);
}

TEST(UnitreeL2Xyz, AllTermsAtIndexTwo) {
  // Point j = 2: α = 0.05 + 0.05 + 2·0.1 = 0.3, θ = 0.1 + 0.1 + 2·0.1 = 0.4, β = 0.1, ξ = 0.2,
  // r = 0.001·(1500 + 10) = 1.51 m, b = 0.02, a = 0.03. By hand:
  // A = (−cosβ sinξ + sinβ cosξ sinα)·r + b = (−0.1976768 + 0.0289154)·1.51 + 0.02 = −0.2348297
  // B = cosα cosξ r = 0.9553365·0.9800666·1.51 = 1.4138030
  // C = (sinβ sinξ + cosβ cosξ sinα)·r = (0.0198339 + 0.2881842)·1.51 = 0.4651073
  // x = cosθ A − sinθ B = 0.9210610·(−0.2348297) − 0.3894183·1.4138030 = −0.766853
  // y = sinθ A + cosθ B = −0.0914470 + 1.3021995 = 1.210751
  // z = C + a = 0.495105
  L2PointSpec s;
  s.angle_min = 0.05F;
  s.alpha_angle_bias = 0.05F;
  s.angle_increment = 0.1F;
  s.com_horizontal_angle_start = 0.1F;
  s.theta_angle_bias = 0.1F;
  s.com_horizontal_angle_step = 0.1F;
  s.beta_angle = 0.1F;
  s.xi_angle = 0.2F;
  s.range_bias = 10.0F;
  s.b_axis_dist = 0.02F;
  s.a_axis_dist = 0.03F;
  s.time_increment = 1e-5F;
  s.ranges[2] = 1500;
  const auto points = decode_one(s);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, -0.766853F, kTol);
  EXPECT_NEAR(points[0].y, 1.210751F, kTol);
  EXPECT_NEAR(points[0].z, 0.495105F, kTol);
  EXPECT_NEAR(static_cast<double>(points[0].time_offset_ns), 20000.0, 2.0);  // 2·10 µs
}

TEST(UnitreeL2Xyz, ZeroAndOutOfRangeReturnsAreSkipped) {
  L2PointSpec s;
  s.range_min = 0.5F;
  s.range_max = 10.0F;
  s.ranges[0] = 0;       // no return
  s.ranges[1] = 400;     // 0.4 m < range_min
  s.ranges[2] = 20000;   // 20 m > range_max
  s.ranges[3] = 5000;    // kept
  s.point_num = 4;
  const auto points = decode_one(s);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].y, 5.0F, kTol);
}

TEST(UnitreeL2Xyz, PointNumBoundsThePoints) {
  L2PointSpec s;
  s.ranges.fill(1000);
  s.point_num = 10;
  EXPECT_EQ(decode_one(s).size(), 10U);
}

TEST(UnitreeL2Xyz, TwoDimensionalModePacket) {
  // 2D mode: x = 0, y = cosα·r, z = sinα·r + a. r = 2 m, a = 0.05:
  // j = 0, α = 30°: y = 1.7320508, z = 1.0 + 0.05 = 1.05
  // j = 1, α = 60°: y = 1.0,       z = 1.7320508 + 0.05 = 1.7820508
  L2Point2dSpec s;
  s.a_axis_dist = 0.05F;
  s.angle_min = static_cast<float>(std::numbers::pi / 6);
  s.angle_increment = static_cast<float>(std::numbers::pi / 6);
  s.ranges[0] = 2000;
  s.ranges[1] = 2000;
  s.intensities[1] = 9;
  DecoderOptions options;  // 18 packets per 3D scan; a 2D packet is a scan of its own
  ASSERT_GE(Decoder::max_points_per_scan(options), 1800U);
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  L2PointSpec partial;
  partial.ranges.fill(1000);
  decoder.push(l2_point_packet(partial), 0);  // a 3D scan begun before a work-mode change
  decoder.push(l2_2d_packet(s), 0);
  ASSERT_EQ(sink.scans.size(), 1U);
  const auto& points = sink.scans[0].points;
  ASSERT_EQ(points.size(), 2U);  // only the 2D packet's points
  EXPECT_EQ(points[0].x, 0.0F);
  EXPECT_NEAR(points[0].y, 1.7320508F, kTol);
  EXPECT_NEAR(points[0].z, 1.05F, kTol);
  EXPECT_NEAR(points[1].y, 1.0F, kTol);
  EXPECT_NEAR(points[1].z, 1.7820508F, kTol);
  EXPECT_EQ(points[1].intensity, 9.0F);
  EXPECT_EQ(decoder.counters().scans, 1U);
}

TEST(UnitreeL2Decoder, ImpossiblePointCountIsMalformed) {
  L2PointSpec s;
  s.ranges.fill(1000);
  s.point_num = 301;
  DecoderOptions options;
  options.packets_per_scan = 1;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  decoder.push(l2_point_packet(s), 0);
  EXPECT_TRUE(sink.scans.empty());
  EXPECT_EQ(decoder.counters().malformed, 1U);
}

L2PointSpec full_packet(std::uint32_t seq, std::uint32_t sec, std::uint32_t nsec) {
  L2PointSpec s;
  s.seq = seq;
  s.stamp_sec = sec;
  s.stamp_nsec = nsec;
  s.ranges.fill(3000);
  s.time_increment = 1e-6F;
  return s;
}

TEST(UnitreeL2Decoder, ScansOf18PacketsWithHostStamps) {
  DecoderOptions options;  // 18 packets per scan, host time
  ASSERT_EQ(Decoder::max_points_per_scan(options), 18U * 300U);
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  for (std::uint32_t i = 0; i < 40; ++i) {
    // Each packet 5 ms after the last on the sensor clock.
    decoder.push(l2_point_packet(full_packet(i, 100, i * 5'000'000)), 1'000'000 + i);
  }
  ASSERT_EQ(sink.scans.size(), 2U);
  EXPECT_EQ(sink.scans[0].points.size(), 18U * 300U);
  EXPECT_EQ(sink.scans[0].stamp_ns, 1'000'000);       // host time of the scan's first packet
  EXPECT_EQ(sink.scans[1].stamp_ns, 1'000'000 + 18);
  // Offsets come from the sensor clock: packet k of the scan starts k·5 ms in.
  EXPECT_EQ(sink.scans[0].points[300].time_offset_ns, 5'000'000U);
  EXPECT_NEAR(static_cast<double>(sink.scans[0].points[301].time_offset_ns), 5'001'000.0, 2.0);
  const auto c = decoder.counters();
  EXPECT_EQ(c.scans, 2U);
  EXPECT_EQ(c.points, 40U * 300U);
  EXPECT_EQ(c.lost_packets, 0U);
}

TEST(UnitreeL2Decoder, SensorTimeStamps) {
  DecoderOptions options;
  options.packets_per_scan = 2;
  options.time_source = TimeSource::sensor;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  decoder.push(l2_point_packet(full_packet(0, 1700000000, 250)), 5);
  decoder.push(l2_point_packet(full_packet(1, 1700000000, 900)), 6);
  ASSERT_EQ(sink.scans.size(), 1U);
  EXPECT_EQ(sink.scans[0].stamp_ns, 1'700'000'000'000'000'250LL);
  EXPECT_EQ(sink.scans[0].receive_ns, 5) << "host time of the scan's first packet, beside the sensor's";
}

// What the clock check gets: each packet's stamp (the L2's time, moved on by a replay's stamp
// offset) with the host time its bytes came with; in host mode the stamp is that host time.
TEST(UnitreeL2Decoder, EveryTimedPacketGivesItsStampAndArrivalToTheSink) {
  for (const TimeSource source : {TimeSource::sensor, TimeSource::host}) {
    DecoderOptions options;
    options.packets_per_scan = 2;
    options.time_source = source;
    VectorSink sink(Decoder::max_points_per_scan(options));
    Decoder decoder(options, sink);
    decoder.set_stamp_offset(1'000);
    L2ImuSpec imu;
    imu.stamp_sec = 1700000000;
    imu.stamp_nsec = 500;
    decoder.push(concat({l2_point_packet(full_packet(0, 1700000000, 250)), l2_imu_packet(imu)}), 5);
    decoder.push(l2_point_packet(full_packet(1, 1700000000, 900)), 6);
    using Times = std::vector<std::pair<std::int64_t, std::int64_t>>;
    const std::int64_t s = 1'700'000'000'000'000'000LL;
    if (source == TimeSource::sensor) {
      EXPECT_EQ(sink.packet_times, (Times{{s + 1'250, 5}, {s + 1'500, 5}, {s + 1'900, 6}}));
      EXPECT_EQ(sink.scans.at(0).stamp_ns, s + 1'250);
      EXPECT_EQ(sink.imu_samples.at(0).stamp_ns, s + 1'500);
    } else {
      EXPECT_EQ(sink.packet_times, (Times{{5, 5}, {5, 5}, {6, 6}}));
    }
  }
}

TEST(UnitreeL2Decoder, SequenceGapsAreCounted) {
  DecoderOptions options;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  decoder.push(l2_point_packet(full_packet(10, 1, 0)), 0);
  decoder.push(l2_point_packet(full_packet(11, 1, 0)), 0);
  decoder.push(l2_point_packet(full_packet(15, 1, 0)), 0);
  EXPECT_EQ(decoder.counters().lost_packets, 3U);
}

TEST(UnitreeL2Decoder, StorageSmallerThanScanIsNeverOverrun) {
  DecoderOptions options;
  options.packets_per_scan = 4;
  VectorSink sink(500);  // less than 4·300
  Decoder decoder(options, sink);
  for (std::uint32_t i = 0; i < 4; ++i) decoder.push(l2_point_packet(full_packet(i, 1, 0)), 0);
  ASSERT_EQ(sink.scans.size(), 1U);
  EXPECT_EQ(sink.scans[0].points.size(), 500U);
  EXPECT_EQ(decoder.counters().dropped_points, 700U);
}

TEST(UnitreeL2Decoder, DatagramsSplitAndMergedGiveTheSameScan) {
  DecoderOptions options;
  options.packets_per_scan = 3;
  Bytes stream;
  for (std::uint32_t i = 0; i < 3; ++i) {
    const Bytes p = concat({l2_point_packet(full_packet(i, 1, i * 1000)), l2_imu_packet({})});
    stream.insert(stream.end(), p.begin(), p.end());
  }
  VectorSink whole(Decoder::max_points_per_scan(options));
  Decoder a(options, whole);
  a.push(stream, 0);
  VectorSink pieces(Decoder::max_points_per_scan(options));
  Decoder b(options, pieces);
  for (std::size_t off = 0; off < stream.size(); off += 333) {
    b.push(std::span<const std::uint8_t>(stream).subspan(off, std::min<std::size_t>(333, stream.size() - off)), 0);
  }
  ASSERT_EQ(whole.scans.size(), 1U);
  ASSERT_EQ(pieces.scans.size(), 1U);
  ASSERT_EQ(whole.scans[0].points.size(), pieces.scans[0].points.size());
  EXPECT_EQ(0, std::memcmp(whole.scans[0].points.data(), pieces.scans[0].points.data(),
                           whole.scans[0].points.size() * sizeof(sim::LidarPoint)));
  EXPECT_EQ(whole.imu_samples.size(), 3U);
  EXPECT_EQ(pieces.imu_samples.size(), 3U);
}

TEST(UnitreeL2Decoder, ImuPacket) {
  L2ImuSpec s;
  s.seq = 42;
  s.stamp_sec = 12;
  s.stamp_nsec = 34;
  s.quaternion_wxyz = {0.9F, 0.1F, 0.2F, 0.3F};
  s.angular_velocity = {0.01F, -0.02F, 0.03F};
  s.linear_acceleration = {0.5F, -0.25F, 9.81F};
  DecoderOptions options;
  options.time_source = TimeSource::sensor;
  VectorSink sink(1);
  Decoder decoder(options, sink);
  decoder.push(l2_imu_packet(s), 99);
  ASSERT_EQ(sink.imu_samples.size(), 1U);
  const auto& imu = sink.imu_samples[0];
  EXPECT_EQ(imu.seq, 42U);
  EXPECT_EQ(imu.stamp_ns, 12'000'000'034LL);
  // Published as (x, y, z, w).
  EXPECT_EQ(imu.quaternion[0], 0.1F);
  EXPECT_EQ(imu.quaternion[1], 0.2F);
  EXPECT_EQ(imu.quaternion[2], 0.3F);
  EXPECT_EQ(imu.quaternion[3], 0.9F);
  EXPECT_EQ(imu.angular_velocity[1], -0.02F);
  EXPECT_EQ(imu.linear_acceleration[2], 9.81F);
  EXPECT_EQ(decoder.counters().imu_samples, 1U);
}

// The decoded samples real L2 units printed (unilidar_sdk2 README, issue #32): the quaternion as
// it came off the wire, and the acceleration measured with it. Read as (w, x, y, z), the
// direction of gravity the quaternion predicts in the sensor frame (the third row of its rotation
// matrix) agrees with the measured acceleration within a few degrees; read as the vendor example
// labels it, (x, y, z, w), it would be off by 45 to 156 degrees.
TEST(UnitreeL2Decoder, ImuQuaternionIsReadAsWxyzAgreeingWithGravityInPublishedSamples) {
  struct Published {
    std::array<float, 4> wire;
    std::array<float, 3> acceleration;
  };
  const Published samples[] = {
      {{-0.3645F, 0.0077F, 0.0099F, 0.9293F}, {0.22F, 0.35F, 9.58F}},
      {{0.9218F, 0.1377F, 0.3574F, 0.0126F}, {-6.46F, 2.88F, 7.27F}},
  };
  for (const Published& p : samples) {
    L2ImuSpec s;
    s.quaternion_wxyz = p.wire;
    s.linear_acceleration = p.acceleration;
    const auto packet = l2_imu_packet(s);
    float first = 0;  // the first float at offset 28 is the wire's first number
    std::memcpy(&first, packet.data() + 28, sizeof first);
    ASSERT_EQ(first, p.wire[0]);
    VectorSink sink(1);
    Decoder decoder(DecoderOptions{}, sink);
    decoder.push(packet, 1);
    ASSERT_EQ(sink.imu_samples.size(), 1U);
    const auto& q = sink.imu_samples[0].quaternion;  // x, y, z, w
    EXPECT_EQ(q[3], p.wire[0]);
    EXPECT_EQ(q[0], p.wire[1]);
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double up[3] = {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    const double a[3] = {p.acceleration[0], p.acceleration[1], p.acceleration[2]};
    const double dot = up[0] * a[0] + up[1] * a[1] + up[2] * a[2];
    const double norms = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]) *
                         std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    const double degrees = std::acos(std::min(1.0, dot / norms)) * 180.0 / std::numbers::pi;
    EXPECT_LT(degrees, 5.0) << "gravity predicted by the quaternion is " << degrees
                            << " degrees off the measured acceleration";
  }
}

// ---- L1 --------------------------------------------------------------------------------------

std::vector<sim::LidarPoint> decode_l1(const std::array<std::uint16_t, 120>& ranges,
                                       const L1AuxSpec& aux) {
  DecoderOptions options;
  options.model = Model::l1;
  options.packets_per_scan = 1;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  decoder.push(concat({l1_distance_frame(aux.packet_id, ranges), l1_auxiliary_frame(aux)}), 0);
  EXPECT_EQ(sink.scans.size(), 1U);
  return sink.scans.empty() ? std::vector<sim::LidarPoint>{} : sink.scans[0].points;
}

TEST(UnitreeL1Xyz, StraightAhead) {
  // All angles 0, b = 0, r = 2.5 m: (0, r, z_bias 0.0445).
  std::array<std::uint16_t, 120> ranges{};
  ranges[0] = 2500;
  L1AuxSpec aux;
  aux.packet_id = 1;
  aux.reflect[0] = 200;
  const auto points = decode_l1(ranges, aux);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, 0.0F, kTol);
  EXPECT_NEAR(points[0].y, 2.5F, kTol);
  EXPECT_NEAR(points[0].z, 0.0445F, kTol);
  EXPECT_EQ(points[0].intensity, 200.0F);
}

TEST(UnitreeL1Xyz, AllTermsAtIndexFive) {
  // j = 5: α = 10° + 5·1° = 15°, β = 30° + 5·12°/120 = 30.5°, θ = 0.05 rad, ξ = 0.1 rad,
  // b = 20 mm, r = 3 m. A = (−cosθ sinξ + sinθ sinα cosξ)·r + b = −0.2594003,
  // B = cosα cosξ r = 2.8833198; x = cosβ A − sinβ B = −1.670619, y = sinβ A + cosβ B = 2.362266,
  // z = (sinθ sinξ + cosθ sinα cosξ)·r + 0.0445 = 0.831081.
  std::array<std::uint16_t, 120> ranges{};
  ranges[5] = 3000;
  L1AuxSpec aux;
  aux.packet_id = 3;
  aux.sys_vertical_angle_start = 10.0F;
  aux.sys_vertical_angle_span = 1.0F;
  aux.com_horizontal_angle_start = 30.0F;
  aux.com_horizontal_angle_step = 12.0F;
  aux.theta_angle = 0.05F;
  aux.ksi_angle = 0.1F;
  aux.b_axis_dist = 20.0F;
  const auto points = decode_l1(ranges, aux);
  ASSERT_EQ(points.size(), 1U);
  EXPECT_NEAR(points[0].x, -1.670619F, kTol);
  EXPECT_NEAR(points[0].y, 2.362266F, kTol);
  EXPECT_NEAR(points[0].z, 0.831081F, kTol);
}

TEST(UnitreeL1Decoder, PairsByPacketIdAndCountsOrphans) {
  DecoderOptions options;
  options.model = Model::l1;
  options.packets_per_scan = 2;
  VectorSink sink(Decoder::max_points_per_scan(options));
  Decoder decoder(options, sink);
  std::array<std::uint16_t, 120> ranges{};
  ranges.fill(1000);
  L1AuxSpec aux;
  aux.packet_id = 1;
  Bytes stream = concat({l1_distance_frame(1, ranges), l1_auxiliary_frame(aux)});
  aux.packet_id = 2;  // its distance packet was lost
  stream = concat({stream, l1_auxiliary_frame(aux)});
  aux.packet_id = 3;  // auxiliary first this time
  stream = concat({stream, l1_distance_frame(9, ranges), l1_auxiliary_frame(aux),
                   l1_distance_frame(3, ranges)});
  decoder.push(stream, 77);
  ASSERT_EQ(sink.scans.size(), 1U);
  EXPECT_EQ(sink.scans[0].points.size(), 240U);
  EXPECT_EQ(sink.scans[0].stamp_ns, 77);
  EXPECT_GE(decoder.counters().unpaired, 2U);
  // The second packet of the scan starts 120 nominal sample periods later.
  EXPECT_GT(sink.scans[0].points[120].time_offset_ns, sink.scans[0].points[119].time_offset_ns);
}

TEST(UnitreeL1Decoder, ImuMessage) {
  DecoderOptions options;
  options.model = Model::l1;
  VectorSink sink(1);
  Decoder decoder(options, sink);
  decoder.push(l1_imu_frame({0.0F, 0.0F, 0.7071F, 0.7071F}, {0.5F, 0.0F, 0.0F},
                            {0.0F, 0.0F, 9.8F}, 17),
               1234);
  ASSERT_EQ(sink.imu_samples.size(), 1U);
  EXPECT_EQ(sink.imu_samples[0].seq, 17U);
  EXPECT_EQ(sink.imu_samples[0].stamp_ns, 1234);
  EXPECT_EQ(sink.imu_samples[0].quaternion[2], 0.7071F);
  EXPECT_EQ(sink.imu_samples[0].angular_velocity[0], 0.5F);
  EXPECT_EQ(sink.imu_samples[0].linear_acceleration[2], 9.8F);
}

TEST(UnitreeModel, Parse) {
  EXPECT_EQ(sim::unitree::parse_model("L2"), Model::l2);
  EXPECT_EQ(sim::unitree::parse_model("l1"), Model::l1);
  EXPECT_EQ(sim::unitree::parse_model("unitree-l2"), Model::l2);
  EXPECT_FALSE(sim::unitree::parse_model("L3").has_value());
}

}  // namespace

namespace {

TEST(UnitreeL2Decoder, ResetDropsThePartialScanAndBufferedBytes) {
  using namespace unitree_test;
  sim::unitree::DecoderOptions options;
  options.packets_per_scan = 2;
  VectorSink sink(sim::unitree::Decoder::max_points_per_scan(options));
  sim::unitree::Decoder decoder(options, sink);
  L2PointSpec s;
  s.ranges.fill(1000);
  const Bytes packet = l2_point_packet(s);
  decoder.push(packet, 0);                                          // half a scan
  decoder.push(std::span<const std::uint8_t>(packet).first(100), 0);   // and part of a packet
  decoder.reset();
  EXPECT_EQ(decoder.counters().framing.truncated, 1U);
  s.ranges.fill(2000);
  const Bytes after = l2_point_packet(s);
  decoder.push(concat({after, after}), 0);
  ASSERT_EQ(sink.scans.size(), 1U);
  ASSERT_EQ(sink.scans[0].points.size(), 600U);
  for (const auto& p : sink.scans[0].points) ASSERT_NEAR(p.y, 2.0F, 1e-4F);  // none from before
}

}  // namespace

// ---- no allocation per packet ------------------------------------------------------------------

#include "allocation_counter.hpp"

namespace {

// Lends fixed storage and keeps nothing: what the SIM sink does with its loaned slot.
class CountingSink : public sim::unitree::ScanSink {
 public:
  explicit CountingSink(std::size_t capacity) : storage_(capacity) {}
  std::span<sim::LidarPoint> begin_scan() override { return storage_; }
  void end_scan(std::size_t, std::int64_t, std::int64_t) override { ++scans; }
  void imu(const sim::unitree::ImuSample&) override { ++imu_samples; }
  int scans = 0;
  int imu_samples = 0;

 private:
  std::vector<sim::LidarPoint> storage_;
};

TEST(UnitreeSteadyState, NoAllocationPerPacketOrScan) {
  using namespace unitree_test;
  for (const auto model : {sim::unitree::Model::l2, sim::unitree::Model::l1}) {
    sim::unitree::DecoderOptions options;
    options.model = model;
    options.packets_per_scan = 3;
    CountingSink sink(sim::unitree::Decoder::max_points_per_scan(options));
    sim::unitree::Decoder decoder(options, sink);
    Bytes stream;
    if (model == sim::unitree::Model::l2) {
      L2PointSpec s;
      s.ranges.fill(1500);
      for (int i = 0; i < 6; ++i) stream = concat({stream, l2_point_packet(s), l2_imu_packet({})});
    } else {
      std::array<std::uint16_t, 120> ranges{};
      ranges.fill(1500);
      for (std::uint16_t id = 0; id < 6; ++id) {
        L1AuxSpec aux;
        aux.packet_id = id;
        stream = concat({stream, l1_distance_frame(id, ranges), l1_auxiliary_frame(aux),
                         l1_imu_frame({0, 0, 0, 1}, {}, {}, id)});
      }
    }
    const std::uint64_t before = unitree_test::allocations();
    for (std::size_t off = 0; off < stream.size(); off += 517) {
      decoder.push(std::span<const std::uint8_t>(stream).subspan(
                       off, std::min<std::size_t>(517, stream.size() - off)),
                   0);
    }
    EXPECT_EQ(unitree_test::allocations(), before) << sim::unitree::to_string(model);
    EXPECT_EQ(sink.scans, 2) << sim::unitree::to_string(model);
    EXPECT_EQ(sink.imu_samples, 6) << sim::unitree::to_string(model);
  }
}

}  // namespace
