// SPDX-License-Identifier: Apache-2.0
// Real recordings decoded and compared with reference clouds (nebula's decoder output), and
// the raw-Ethernet Pandar40P capture cut into whole 20 Hz revolutions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "pcap_payloads.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;
using hesai_test::data_path;

namespace {

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
    if (auto f = assembler.flush()) take(*f);
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

void expect_matches_reference(Model model, const char* pcap, const char* calibration,
                              const char* pcd, float min_range, float max_range) {
  const auto packets = hesai_test::read_udp_payloads(data_path(pcap));
  ASSERT_FALSE(packets.empty());
  auto cal = Calibration::load(data_path(calibration), model);
  ASSERT_TRUE(cal) << cal.error().message;
  auto assembler = FrameAssembler::create(*cal, nebula_options(model, min_range, max_range));
  ASSERT_TRUE(assembler) << assembler.error().message;
  const auto frames = decode_all(*assembler, packets, frame_capacity(model, 2));
  ASSERT_GE(frames.size(), 2u);
  EXPECT_EQ(assembler->counters().malformed, 0u);
  EXPECT_EQ(assembler->counters().lost_packets, 0u);
  EXPECT_EQ(assembler->counters().dropped_points, 0u);

  const auto reference = hesai_test::read_xyz_pcd(data_path(pcd));
  ASSERT_FALSE(reference.empty());
  // The reference revolution is the whole frame whose first point is the reference's first.
  const DecodedFrame* match = nullptr;
  for (const auto& f : frames) {
    if (!f.info.whole_revolution || f.points.empty()) continue;
    const auto& p = f.points.front();
    if (std::abs(p.x - reference[0].x) < 1e-3f && std::abs(p.y - reference[0].y) < 1e-3f &&
        std::abs(p.z - reference[0].z) < 1e-3f) {
      match = &f;
    }
  }
  ASSERT_NE(match, nullptr) << "no decoded revolution starts with the reference's first point";
  ASSERT_EQ(match->points.size(), reference.size());
  float worst = 0;
  std::size_t worst_index = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const auto& p = match->points[i];
    const float d = std::max({std::abs(p.x - reference[i].x), std::abs(p.y - reference[i].y),
                              std::abs(p.z - reference[i].z)});
    if (d > worst) {
      worst = d;
      worst_index = i;
    }
  }
  EXPECT_LT(worst, 1e-3f) << "point " << worst_index << " is " << worst << " m off";
  ::testing::Test::RecordProperty("largest_difference_m", std::to_string(worst));
}

}  // namespace

TEST(HesaiReference, Pandar64DualMatchesNebulaReferenceCloud) {
  expect_matches_reference(Model::pandar64, "pandar64_dual.pcap", "pandar64.calibration.csv",
                           "pandar64_dual.reference.pcd", 0.3f, 200.0f);
}

TEST(HesaiReference, PandarXT32DualMatchesNebulaReferenceCloud) {
  expect_matches_reference(Model::pandar_xt32, "pandarxt32_dual.pcap",
                           "pandarxt32.calibration.csv", "pandarxt32_dual.reference.pcd", 0.05f,
                           120.0f);
}
