// SPDX-License-Identifier: Apache-2.0
// Real recordings decoded and compared with reference clouds (nebula's decoder output): one
// table of golden cases (capture, calibration, model options, reference cloud, tolerance) and
// one parameterised test over it, the shape every family's golden tests share
// (tests/support/lidar_test/golden.hpp). Then the QT128 capture's packets one by one, and the
// raw-Ethernet Pandar40P capture cut into whole 20 Hz revolutions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "hesai_test_data.hpp"
#include "lidar_test/golden.hpp"
#include "sim/hesai/hesai.hpp"

namespace {

using namespace sim::hesai;
using hesai_test::data_path;
using lidar_test::Tolerance;

struct DecodedFrame {
  CompletedFrame info;
  std::vector<sim::LidarPoint> points;
};

// Decodes every payload into frames, swapping in a fresh buffer after each one as a driver
// swaps in a fresh loan.
std::vector<DecodedFrame> decode_all(FrameAssembler& assembler,
                                     const std::vector<hesai_test::UdpPayload>& packets,
                                     std::size_t capacity, bool flush_at_end = false) {
  std::vector<DecodedFrame> frames;
  std::vector<sim::LidarPoint> buffer(capacity);
  assembler.set_output(buffer);
  auto take = [&](const CompletedFrame& f) {
    frames.push_back({f, std::vector<sim::LidarPoint>(buffer.begin(),
                                                      buffer.begin() + static_cast<std::ptrdiff_t>(f.point_count))});
    std::fill(buffer.begin(), buffer.end(), sim::LidarPoint{});  // a fresh slot
    assembler.set_output(buffer);
  };
  for (const auto& p : packets) {
    const PushResult r = assembler.push(p.bytes, p.capture_ns);
    EXPECT_EQ(r.error, PacketError::none) << to_string(r.error);
    if (r.frame) take(*r.frame);
  }
  if (flush_at_end) {
    if (auto f = assembler.finish()) take(*f);
  }
  return frames;
}

// The settings SOURCES.md gives for the reference clouds, spelled out as configuration.
AssemblerOptions nebula_options(Model model, float min_range, float max_range) {
  AssemblerOptions o;
  o.model = model;
  o.cut_azimuth_deg = 0.0;
  o.min_range_m = min_range;
  o.max_range_m = max_range;
  o.drop_zero_distance = true;
  o.drop_identical_returns = true;
  o.multi_return_distance_threshold_m = 0.1f;
  return o;
}

// One golden case: a capture decoded with its calibration and options, against the reference
// revolution, which is the whole decoded frame whose first point is the reference's first.
struct GoldenCase {
  std::string name;
  const char* capture;
  const char* calibration;
  AssemblerOptions options;
  const char* reference;
  Tolerance tolerance;
};

// Every point within 1 mm on each axis.
constexpr Tolerance every_point_within_1mm{Tolerance::Distance::largest_axis, 1e-3, 1.0};

const GoldenCase golden_cases[] = {
    {"Pandar64Dual", "pandar64_dual.pcap", "pandar64.calibration.csv",
     nebula_options(Model::pandar64, 0.3f, 200.0f), "pandar64_dual.reference.pcd", every_point_within_1mm},
    {"PandarXT32Dual", "pandarxt32_dual.pcap", "pandarxt32.calibration.csv",
     nebula_options(Model::pandar_xt32, 0.05f, 120.0f), "pandarxt32_dual.reference.pcd", every_point_within_1mm},
    // nebula's test configuration for this capture: range 0.3–300 m (wider than the sensor's own
    // 0.05–50 m defaults).
    {"PandarQT128Dual", "pandarqt128_dual.pcap", "pandarqt128.calibration.csv",
     nebula_options(Model::pandar_qt128, 0.3f, 300.0f), "pandarqt128_dual.reference.pcd", every_point_within_1mm},
};

class HesaiReferenceCloud : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(HesaiReferenceCloud, DecodedRevolutionMatchesNebulasReferenceCloud) {
  const GoldenCase& c = GetParam();
  const auto packets = hesai_test::read_udp_payloads(data_path(c.capture));
  ASSERT_FALSE(packets.empty());
  auto cal = Calibration::load(data_path(c.calibration), c.options.model);
  ASSERT_TRUE(cal) << cal.error().message;
  auto assembler = FrameAssembler::create(*cal, c.options);
  ASSERT_TRUE(assembler) << assembler.error().message;
  const auto frames = decode_all(*assembler, packets, frame_capacity(c.options.model, 2));
  ASSERT_GE(frames.size(), 1u);  // the QT128 capture holds one whole revolution
  EXPECT_EQ(assembler->counters().malformed, 0u);
  EXPECT_EQ(assembler->counters().lost_packets, 0u);
  EXPECT_EQ(assembler->counters().dropped_points, 0u);

  const auto reference = lidar_test::read_xyz_pcd(data_path(c.reference));
  ASSERT_FALSE(reference.empty());
  // The last whole revolution that starts with the reference's first point.
  const DecodedFrame* match = nullptr;
  for (const auto& f : frames) {
    if (!f.info.whole || f.points.empty()) continue;
    lidar_test::CloudComparison first(c.tolerance);
    first.add(f.points.front(), reference.front());
    if (first.holds()) match = &f;
  }
  ASSERT_NE(match, nullptr) << "no decoded revolution starts with the reference's first point";
  ASSERT_EQ(match->points.size(), reference.size());
  const auto comparison = lidar_test::compare_clouds(match->points, reference, c.tolerance);
  EXPECT_TRUE(comparison.holds()) << comparison.describe() << " (" << c.tolerance << ")";
  RecordProperty("largest_difference_m", std::to_string(comparison.largest_m()));
}

INSTANTIATE_TEST_SUITE_P(Nebula, HesaiReferenceCloud, ::testing::ValuesIn(golden_cases), lidar_test::CaseName{});

TEST(HesaiReference, EveryPandarQT128PacketPassesItsCrcsAndReportsItsSafetyState) {
  const auto packets = hesai_test::read_udp_payloads(data_path("pandarqt128_dual.pcap"));
  ASSERT_EQ(packets.size(), 1800u);
  std::set<unsigned> loops;
  for (const auto& p : packets) {
    ASSERT_EQ(detect_model(p.bytes), Model::pandar_qt128);
    Packet packet;
    ASSERT_EQ(Packet::parse(p.bytes, Model::pandar_qt128, packet), PacketError::none);
    EXPECT_EQ(packet.returns(), 2u);
    EXPECT_EQ(packet.motor_rpm(), 600);
    const auto safety = packet.functional_safety();
    ASSERT_TRUE(safety.has_value());
    // The recording's sensor reports no fault (state 0, "initialization", throughout).
    EXPECT_EQ(safety->fault_type, FaultCodeType::none);
    EXPECT_EQ(safety->state, LidarState::initialization);
    loops.insert(packet.firing_loop(0));
    // A channel dark in the packet's firing loop has no return.
    const unsigned dark_first = packet.firing_loop(0) == 0 ? 0 : 32;
    for (unsigned ch = dark_first; ch < dark_first + 32; ++ch) {
      ASSERT_EQ(packet.raw_distance(0, ch), 0) << "channel " << ch;
      ASSERT_EQ(packet.raw_distance(1, ch), 0) << "channel " << ch;
    }
  }
  EXPECT_EQ(loops, (std::set<unsigned>{0, 1}));  // the loops alternate
}

// Reference §3 layout, read here straight from the bytes: the points one revolution must hold.
// A point belongs to the revolution its own azimuth (block azimuth + channel offset) is in.
std::map<long, std::size_t> expected_pandar40p_points(
    const std::vector<hesai_test::UdpPayload>& packets, const Calibration& cal) {
  std::map<long, std::size_t> per_revolution;
  long unwrapped_base = 0;
  int last_azimuth = -1;
  for (const auto& p : packets) {
    for (unsigned b = 0; b < 10; ++b) {
      const std::uint8_t* block = p.bytes.data() + 124 * b;
      const int azimuth = block[2] | (block[3] << 8);
      if (last_azimuth >= 0 && azimuth < last_azimuth) unwrapped_base += 36000;
      last_azimuth = azimuth;
      for (unsigned c = 0; c < 40; ++c) {
        const int raw = block[4 + 3 * c] | (block[5 + 3 * c] << 8);
        const double metres = raw * 0.004;
        if (raw == 0 || metres < 0.3 || metres > 200.0) continue;
        const double point_azimuth = static_cast<double>(unwrapped_base) + azimuth + cal[c].azimuth_offset_deg * 100.0;
        ++per_revolution[static_cast<long>(std::floor(point_azimuth / 36000.0))];
      }
    }
  }
  return per_revolution;
}

TEST(HesaiReference, RawEthernetPandar40PGivesWholeRevolutionsAt20Hz) {
  // Read through the Ethernet/IPv4/UDP headers of a real pcapng capture.
  const auto packets = hesai_test::read_udp_payloads(data_path("pandar40p_last_20hz_raw.pcapng"));
  ASSERT_EQ(packets.size(), 200u);
  for (const auto& p : packets) {
    ASSERT_EQ(p.dst_port, 2369);
    ASSERT_EQ(detect_model(p.bytes), Model::pandar40p);
  }
  auto cal = Calibration::load(data_path("pandar40p.example-calibration.csv"), Model::pandar40p);
  ASSERT_TRUE(cal) << cal.error().message;
  AssemblerOptions options;
  options.model = Model::pandar40p;
  auto assembler = FrameAssembler::create(*cal, options);
  ASSERT_TRUE(assembler);
  const auto frames = decode_all(*assembler, packets, frame_capacity(Model::pandar40p, 1, 1200),
                                 /*flush_at_end=*/true);
  const auto& c = assembler->counters();
  EXPECT_EQ(c.packets, 200u);
  EXPECT_EQ(c.lost_packets, 0u);
  EXPECT_EQ(c.out_of_order, 0u);
  EXPECT_EQ(c.malformed, 0u);
  EXPECT_EQ(c.dropped_points, 0u);

  // 200 packets × 10 firings × 0.4° = 2.2 turns starting at 129.8°: one whole revolution
  // between two partial ones (the first is not published, the last comes from finish()).
  ASSERT_EQ(frames.size(), 2u);
  const auto& whole = frames[0];
  EXPECT_TRUE(whole.info.whole);
  EXPECT_FALSE(frames[1].info.whole);
  EXPECT_EQ(whole.info.lost_packets, 0u);
  // 20 Hz at 0.4° per firing: 900 firings in 90 packets, plus those whose points straddle a
  // cut: the calibration's azimuth offsets spread over 8.3°, about 2 packets of 4°.
  EXPECT_GE(whole.info.packets, 90u);
  EXPECT_LE(whole.info.packets, 94u);
  const auto expected = expected_pandar40p_points(packets, *cal);
  ASSERT_EQ(expected.count(1), 1u);
  EXPECT_EQ(whole.info.point_count, expected.at(1));
  EXPECT_LE(whole.info.point_count, 40u * 900u);  // channels × firings × 1 return
  EXPECT_EQ(frames[1].info.point_count, expected.at(2));

  // One revolution at 20 Hz lasts 50 ms of sensor time: the last firing is ~50 ms after the
  // stamp, and the next frame's stamp is 50 ms later.
  std::uint32_t last_offset = 0;
  for (const auto& p : whole.points) last_offset = std::max(last_offset, p.time_offset_ns);
  EXPECT_GT(last_offset, 48'000'000u);
  EXPECT_LT(last_offset, 52'000'000u);
  const std::int64_t period = frames[1].info.stamp_ns - whole.info.stamp_ns;
  EXPECT_GT(period, 49'000'000);
  EXPECT_LT(period, 51'000'000);
  // Sensor time: 2017-09-06 16:09:43 UTC (year byte 17, counted from 2000).
  EXPECT_EQ(whole.info.stamp_ns / 1'000'000'000, 1504714183);
  // The frame starts at azimuth 0° and ends just before 360°.
  const auto azimuth = [](const sim::LidarPoint& p) {
    const double a = std::atan2(p.x, p.y) * 180.0 / M_PI;
    return a < 0 ? a + 360.0 : a;
  };
  EXPECT_LT(azimuth(whole.points.front()), 1.0);
  EXPECT_GT(azimuth(whole.points.back()), 359.0);
}

}  // namespace
