// SPDX-License-Identifier: Apache-2.0
// FrameAssembler behaviour a driver relies on, on the real Pandar64 capture: where frames are
// cut, the hand-over of the straddling points between spans, loss and reorder counting, a span
// that is too small, a caller that forgets set_output, the filter options and point times.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "packet_builder.hpp"
#include "hesai_test_data.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;
using hesai_test::data_path;

namespace {

using Payloads = std::vector<hesai_test::UdpPayload>;

const Payloads& pandar64_packets() {
  static const Payloads packets = hesai_test::read_udp_payloads(data_path("pandar64_dual.pcap"));
  return packets;
}

const Calibration& pandar64_calibration() {
  static const Calibration cal = [] {
    auto c = Calibration::load(data_path("pandar64.calibration.csv"), Model::pandar64);
    if (!c) throw std::runtime_error(c.error().message);
    return *c;
  }();
  return cal;
}

FrameAssembler make(AssemblerOptions options = {}) {
  auto a = FrameAssembler::create(pandar64_calibration(), std::move(options));
  if (!a) throw std::runtime_error(a.error().message);
  return std::move(*a);
}

struct Frame {
  CompletedFrame info;
  std::vector<sim::LidarPoint> points;
};

// Like a driver: each frame goes to its own fresh span (a new loan), given after completion.
std::vector<Frame> run(FrameAssembler& a, const Payloads& packets, std::size_t capacity,
                       bool flush = false) {
  std::vector<Frame> frames;
  auto span = std::make_unique<std::vector<sim::LidarPoint>>(capacity);
  a.set_output(*span);
  auto take = [&](const CompletedFrame& f) {
    frames.push_back({f, std::vector<sim::LidarPoint>(
                             span->begin(), span->begin() + static_cast<std::ptrdiff_t>(f.point_count))});
    span = std::make_unique<std::vector<sim::LidarPoint>>(capacity);  // a different slot
    a.set_output(*span);
  };
  for (const auto& p : packets) {
    const PushResult r = a.push(p.bytes, p.capture_ns);
    if (r.frame) take(*r.frame);
  }
  if (flush) {
    if (auto f = a.finish()) take(*f);
  }
  return frames;
}

std::size_t capacity() { return frame_capacity(Model::pandar64, 2); }

double azimuth_deg(const sim::LidarPoint& p) {
  const double a = std::atan2(p.x, p.y) * 180.0 / M_PI;
  return a < 0 ? a + 360.0 : a;
}

bool same_points(const std::vector<sim::LidarPoint>& a, const std::vector<sim::LidarPoint>& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(sim::LidarPoint)) == 0;
}

}  // namespace

TEST(HesaiAssembler, FramesAreWholeRevolutionsWithSensorStampsAndPointTimes) {
  auto a = make();
  const auto frames = run(a, pandar64_packets(), capacity());
  ASSERT_GE(frames.size(), 2u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    EXPECT_TRUE(f.info.whole);
    EXPECT_EQ(f.info.index, i);
    EXPECT_LE(f.info.point_count, capacity());
    // The first point is just past 0°, the last just before 360°.
    EXPECT_LT(azimuth_deg(f.points.front()), 1.0);
    EXPECT_GT(azimuth_deg(f.points.back()), 359.0);
    std::uint32_t last = 0;
    for (const auto& p : f.points) {
      last = std::max(last, p.time_offset_ns);
      ASSERT_LT(p.ring, 64);
      ASSERT_LT(p.return_index, 2);
    }
    // A revolution at 10 Hz lasts 100 ms of sensor time, plus the time the head takes to
    // turn through the calibration's azimuth-offset spread (10.4° = 2.9 ms): a frame holds
    // the points by their own azimuth, so its first and last firings are that much further apart.
    EXPECT_GT(last, 100'000'000u);
    EXPECT_LT(last, 104'000'000u);
    if (i > 0) {
      const std::int64_t period = f.info.stamp_ns - frames[i - 1].info.stamp_ns;
      EXPECT_GT(period, 99'000'000);
      EXPECT_LT(period, 101'000'000);
      EXPECT_GT(f.info.host_receive_ns, frames[i - 1].info.host_receive_ns);
    }
  }
}

// The live driver sleeps through time_to_cut_ns() (less a 1 ms margin) instead of waking per
// packet: it must never promise time that is not there, and should promise what is.
TEST(HesaiAssembler, TimeToCutPredictsWhenTheNextFrameCompletes) {
  for (const double cut_deg : {0.0, 137.5}) {
    SCOPED_TRACE(cut_deg);
    AssemblerOptions options;
    options.cut_azimuth_deg = cut_deg;
    auto a = make(options);
    std::vector<sim::LidarPoint> span(capacity());
    a.set_output(span);
    EXPECT_FALSE(a.time_to_cut_ns().has_value()) << "before the first packet";
    const Payloads& packets = pandar64_packets();
    std::vector<std::int64_t> predicted(packets.size(), -1);
    std::vector<std::size_t> completing;
    for (std::size_t i = 0; i < packets.size(); ++i) {
      if (i > 0) predicted[i] = a.time_to_cut_ns().value_or(-1);
      if (a.push(packets[i].bytes, packets[i].capture_ns).frame) {
        completing.push_back(i);
        a.set_output(span);
      }
    }
    ASSERT_GE(completing.size(), 2u);
    std::size_t checked = 0;
    for (std::size_t f = 1; f < completing.size(); ++f) {
      const std::size_t cut = completing[f];
      // Before the completing packet no nap may be left (the driver keeps a 1 ms margin).
      EXPECT_LT(predicted[cut], 500'000) << "packet " << cut;
      // Through the revolution, the prediction follows the capture's own clock.
      for (std::size_t i = completing[f - 1] + 1; i <= cut; ++i) {
        const std::int64_t actual = packets[cut].capture_ns - packets[i - 1].capture_ns;
        ASSERT_GE(predicted[i], 0) << "packet " << i;
        EXPECT_NEAR(static_cast<double>(predicted[i]), static_cast<double>(actual), 2e6) << "packet " << i;
        ++checked;
      }
    }
    EXPECT_GT(checked, 500u);
  }
}

TEST(HesaiAssembler, CutAtAnotherAzimuth) {
  AssemblerOptions options;
  options.cut_azimuth_deg = 180.0;
  auto a = make(options);
  const auto frames = run(a, pandar64_packets(), capacity());
  ASSERT_GE(frames.size(), 3u);  // 4 turns starting near 0°: three 180°→180° revolutions
  for (const auto& f : frames) {
    EXPECT_GE(azimuth_deg(f.points.front()), 180.0);
    EXPECT_LT(azimuth_deg(f.points.front()), 181.0);
    EXPECT_LT(azimuth_deg(f.points.back()), 180.0);
    EXPECT_GT(azimuth_deg(f.points.back()), 179.0);
  }
  // By block azimuth, whole firings stay together: channels with a +5.2° offset spill over.
  options.cut_by = CutBy::block_azimuth;
  auto b = make(options);
  const auto by_block = run(b, pandar64_packets(), capacity());
  ASSERT_EQ(by_block.size(), frames.size());
  for (const auto& f : by_block) {
    // The first firing's block azimuth (point azimuth minus its channel's offset) is the
    // first at or past 180°, 0.2° apart at 10 Hz.
    const auto& p = f.points.front();
    const double block = azimuth_deg(p) - pandar64_calibration()[p.ring].azimuth_offset_deg;
    EXPECT_GE(block, 180.0 - 1e-3);
    EXPECT_LT(block, 180.2);
  }
}

TEST(HesaiAssembler, StraddlingPointsMoveToTheNextSpanUnchanged) {
  // One big span that is never swapped would need no carry-over: decode every frame into its
  // own span (run) and compare with a decode into a single reused buffer copied out.
  auto a = make();
  const auto swapped = run(a, pandar64_packets(), capacity());
  auto b = make();
  std::vector<sim::LidarPoint> buffer(capacity());
  std::vector<Frame> reused;
  b.set_output(buffer);
  for (const auto& p : pandar64_packets()) {
    if (auto f = b.push(p.bytes, p.capture_ns).frame) {
      reused.push_back({*f, std::vector<sim::LidarPoint>(buffer.begin(),
                                                         buffer.begin() + static_cast<std::ptrdiff_t>(f->point_count))});
      b.set_output(buffer);
    }
  }
  ASSERT_EQ(swapped.size(), reused.size());
  for (std::size_t i = 0; i < swapped.size(); ++i) {
    EXPECT_TRUE(same_points(swapped[i].points, reused[i].points)) << "frame " << i;
    EXPECT_EQ(swapped[i].info.stamp_ns, reused[i].info.stamp_ns);
  }
}

TEST(HesaiAssembler, LostPacketsAreCountedFromTheUdpSequence) {
  Payloads packets = pandar64_packets();
  packets.erase(packets.begin() + 1000, packets.begin() + 1005);
  auto a = make();
  const auto frames = run(a, packets, capacity());
  EXPECT_EQ(a.counters().lost_packets, 5u);
  EXPECT_EQ(a.counters().out_of_order, 0u);
  std::uint32_t in_frames = 0;
  for (const auto& f : frames) in_frames += f.info.lost_packets;
  EXPECT_EQ(in_frames, 5u);
}

TEST(HesaiAssembler, LostPacketsAreCountedFromAzimuthGapsWithoutSequence) {
  Payloads packets = pandar64_packets();
  for (auto& p : packets) p.bytes.resize(1194);  // the sensor's sequence-less packet size
  packets.erase(packets.begin() + 900, packets.begin() + 903);
  auto a = make();
  const auto frames = run(a, packets, capacity());
  EXPECT_EQ(a.counters().malformed, 0u);
  EXPECT_EQ(a.counters().lost_packets, 3u);
  EXPECT_GE(frames.size(), 2u);
}

TEST(HesaiAssembler, AReorderedPacketIsCountedAndKeptInItsFrame) {
  auto a = make();
  const auto original = run(a, pandar64_packets(), capacity());
  Payloads packets = pandar64_packets();
  std::swap(packets[1500], packets[1501]);
  auto b = make();
  const auto reordered = run(b, packets, capacity());
  EXPECT_EQ(b.counters().out_of_order, 1u);
  ASSERT_EQ(reordered.size(), original.size());  // no spurious cut
  for (std::size_t i = 0; i < original.size(); ++i) {
    EXPECT_EQ(reordered[i].info.point_count, original[i].info.point_count);
  }
}

TEST(HesaiAssembler, ASpanTooSmallKeepsItsFrontAndCountsTheRest) {
  auto a = make();
  const auto full = run(a, pandar64_packets(), capacity());
  auto b = make();
  const auto small = run(b, pandar64_packets(), 5000);
  ASSERT_EQ(small.size(), full.size());
  for (std::size_t i = 0; i < full.size(); ++i) {
    EXPECT_EQ(small[i].info.point_count, 5000u);
    EXPECT_EQ(small[i].info.dropped_points, full[i].info.point_count - 5000);
    EXPECT_TRUE(std::equal(small[i].points.begin(), small[i].points.end(), full[i].points.begin(),
                           [](const auto& x, const auto& y) {
                             return std::memcmp(&x, &y, sizeof x) == 0;
                           }));
  }
}

TEST(HesaiAssembler, ForgettingSetOutputDropsFramesButNeverWritesAnywhere) {
  auto a = make();
  std::vector<sim::LidarPoint> span(capacity());
  a.set_output(span);
  std::size_t returned = 0;
  for (const auto& p : pandar64_packets()) {
    if (a.push(p.bytes, p.capture_ns).frame) ++returned;  // never calls set_output again
  }
  EXPECT_EQ(returned, 1u);
  EXPECT_GE(a.counters().frames_without_output, 1u);
  EXPECT_GT(a.counters().dropped_points, 0u);
}

TEST(HesaiAssembler, AFirstSpanGivenLateStartsCleanAtTheNextCut) {
  // A driver that attaches its first span only after the first cut: the partial revolution
  // decoded before has nowhere to go and must not leak into the next frame.
  AssemblerOptions options;
  options.cut_by = CutBy::block_azimuth;  // the frame after the cut is then still whole
  const auto& packets = pandar64_packets();
  // The packet holding the first cut: where a partial frame is returned when asked for.
  std::size_t first_cut = 0;
  {
    AssemblerOptions partial = options;
    partial.emit_partial_frames = true;
    auto a = make(partial);
    std::vector<sim::LidarPoint> span(capacity());
    a.set_output(span);
    while (first_cut < packets.size() &&
           !a.push(packets[first_cut].bytes, packets[first_cut].capture_ns).frame) {
      ++first_cut;
    }
  }
  ASSERT_LT(first_cut, packets.size());
  auto normal = make(options);
  const auto expected = run(normal, packets, capacity());
  ASSERT_FALSE(expected.empty());

  auto late = make(options);
  for (std::size_t i = 0; i <= first_cut; ++i) {
    EXPECT_FALSE(late.push(packets[i].bytes, packets[i].capture_ns).frame);
  }
  std::vector<sim::LidarPoint> late_span(capacity());
  late.set_output(late_span);
  std::optional<CompletedFrame> frame;
  for (std::size_t i = first_cut + 1; i < packets.size() && !frame; ++i) {
    frame = late.push(packets[i].bytes, packets[i].capture_ns).frame;
  }
  ASSERT_TRUE(frame);
  EXPECT_TRUE(frame->whole);
  EXPECT_EQ(frame->stamp_ns, expected[0].info.stamp_ns);
  ASSERT_EQ(frame->point_count, expected[0].points.size());
  EXPECT_EQ(std::memcmp(late_span.data(), expected[0].points.data(),
                        expected[0].points.size() * sizeof(sim::LidarPoint)),
            0);
}

TEST(HesaiAssembler, PartialFramesOnRequestAndFlushAtTheEnd) {
  AssemblerOptions options;
  options.emit_partial_frames = true;
  auto a = make(options);
  const auto frames = run(a, pandar64_packets(), capacity(), /*flush=*/true);
  auto b = make();
  const auto whole_only = run(b, pandar64_packets(), capacity());
  ASSERT_EQ(frames.size(), whole_only.size() + 2);
  EXPECT_FALSE(frames.front().info.whole);
  EXPECT_FALSE(frames.back().info.whole);
  EXPECT_TRUE(same_points(frames[1].points, whole_only[0].points));
  // Every packet went somewhere: 2400 packets counted once, plus the straddling ones twice.
  std::uint32_t packets = 0;
  for (const auto& f : frames) packets += f.info.packets;
  EXPECT_GE(packets, 2400u);
  EXPECT_LT(packets, 2400u + 5 * 30);
  // reset() starts over as a fresh assembler would (a looping replay).
  a.reset();
  const auto again = run(a, pandar64_packets(), capacity(), true);
  ASSERT_EQ(again.size(), frames.size());
  EXPECT_TRUE(same_points(again[1].points, frames[1].points));
  EXPECT_EQ(a.counters().lost_packets, 0u);
}

TEST(HesaiAssembler, FilterOptionsDoWhatTheySay) {
  auto base = make();
  const auto reference = run(base, pandar64_packets(), capacity());

  AssemblerOptions keep_all;
  keep_all.drop_identical_returns = false;
  keep_all.multi_return_distance_threshold_m = 0.0f;
  auto a = make(keep_all);
  const auto more = run(a, pandar64_packets(), capacity());
  ASSERT_EQ(more.size(), reference.size());
  EXPECT_GT(more[0].info.point_count, reference[0].info.point_count);

  AssemblerOptions with_zeros;
  with_zeros.drop_zero_distance = false;
  with_zeros.min_range_m = 0.0f;
  auto b = make(with_zeros);
  const auto zeros = run(b, pandar64_packets(), capacity() * 2);
  ASSERT_EQ(zeros.size(), reference.size());
  const auto at_origin = std::count_if(zeros[0].points.begin(), zeros[0].points.end(),
                                       [](const auto& p) { return p.x == 0 && p.y == 0 && p.z == 0; });
  EXPECT_GT(at_origin, 0);

  AssemblerOptions near;
  near.max_range_m = 10.0f;
  auto c = make(near);
  const auto close = run(c, pandar64_packets(), capacity());
  ASSERT_EQ(close.size(), reference.size());
  EXPECT_LT(close[0].info.point_count, reference[0].info.point_count);
  for (const auto& p : close[0].points) {
    ASSERT_LE(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 10.0f + 1e-4f);
  }

  AssemblerOptions bad;
  bad.min_range_m = 5.0f;
  bad.max_range_m = 1.0f;
  EXPECT_FALSE(FrameAssembler::create(pandar64_calibration(), bad));
  bad = {};
  bad.multi_return_distance_threshold_m = -1.0f;
  EXPECT_FALSE(FrameAssembler::create(pandar64_calibration(), bad));
}

TEST(HesaiAssembler, FiretimeFileGivesTheSameTimesAndOptionallyRotatesPoints) {
  auto fire = FiretimeCorrection::load(data_path("pandar64.example-firetimes.csv"), Model::pandar64);
  ASSERT_TRUE(fire);
  auto base = make();
  const auto reference = run(base, pandar64_packets(), capacity());

  AssemblerOptions with_file;
  with_file.firetimes = *fire;
  auto a = make(with_file);
  const auto same = run(a, pandar64_packets(), capacity());
  ASSERT_EQ(same.size(), reference.size());
  EXPECT_TRUE(same_points(same[0].points, reference[0].points));

  with_file.firetime_azimuth_compensation = true;
  with_file.cut_by = CutBy::block_azimuth;
  auto b = make(with_file);
  AssemblerOptions block_cut;
  block_cut.cut_by = CutBy::block_azimuth;
  auto c = make(block_cut);
  const auto rotated = run(b, pandar64_packets(), capacity());
  const auto unrotated = run(c, pandar64_packets(), capacity());
  ASSERT_EQ(rotated.size(), unrotated.size());
  ASSERT_EQ(rotated[0].info.point_count, unrotated[0].info.point_count);
  // Ring 0 fires 23.18 µs before its block; at ~600 rpm the head turns 23.18·600·6e-6 =
  // 0.0834° in that time, which the compensation subtracts from its azimuth.
  for (std::size_t i = 0; i < rotated[0].points.size(); ++i) {
    const auto& r = rotated[0].points[i];
    if (r.ring != 0 || std::hypot(r.x, r.y) < 2.0f) continue;
    double delta = azimuth_deg(r) - azimuth_deg(unrotated[0].points[i]);
    if (delta > 180) delta -= 360;
    if (delta < -180) delta += 360;
    EXPECT_NEAR(delta, -23.18 * 600 * 6e-6, 0.001);
    break;
  }
}

namespace {

// Packets of `revolutions` turns at 10 Hz built from the layout tables, for the models without
// a public capture. Azimuth starts at 0°, every channel returns, the UTC fields advance.
std::vector<std::vector<std::uint8_t>> synthetic_turns(Model model, unsigned returns,
                                                       double revolutions) {
  const ModelInfo& m = info(model);
  const unsigned groups = m.blocks_per_packet / returns;
  const unsigned step = m.azimuth_step_10hz;
  const auto packets = static_cast<unsigned>(revolutions * 36000 / (step * groups));
  const double packet_us = 100000.0 / (36000.0 / (step * groups));  // 100 ms per turn
  std::vector<std::vector<std::uint8_t>> out;
  for (unsigned k = 0; k < packets; ++k) {
    hesai_test::SyntheticPacket s;
    s.channels = m.channels;
    s.blocks = m.blocks_per_packet;
    s.returns = returns;
    s.return_mode = returns == 3 ? 0x3d : returns == 2 ? 0x39 : 0x38;
    s.first_azimuth = static_cast<std::uint16_t>((k * groups * step) % 36000);
    s.azimuth_step = static_cast<std::uint16_t>(step);
    const auto us = static_cast<std::uint64_t>(k * packet_us);
    s.utc[5] = static_cast<std::uint8_t>(7 + us / 1000000);
    s.micros = static_cast<std::uint32_t>(us % 1000000);
    s.sequence = 1000 + k;
    // 1 to 40 m: inside every model's range limits (QT64: 0.1–60 m).
    s.distance = [](unsigned, unsigned ch) { return static_cast<std::uint16_t>((ch % 40 + 1) * 250); };
    out.push_back(model == Model::pandar_qt64 ? hesai_test::build_qt64(s) : hesai_test::build_xt(s));
  }
  return out;
}

}  // namespace

TEST(HesaiAssembler, SyntheticXT16QT64AndXT32MTurnsHaveEveryFiringOfARevolution) {
  for (const Model model : {Model::pandar_xt16, Model::pandar_qt64, Model::pandar_xt32m}) {
    for (const unsigned returns : {1u, 2u, 3u}) {
      if (returns > info(model).max_returns) continue;
      SCOPED_TRACE(std::string(to_string(model)) + " returns " + std::to_string(returns));
      const ModelInfo& m = info(model);
      auto cal = Calibration::from_angles(std::vector<ChannelAngles>(m.channels, {0.0f, 0.0f}));
      ASSERT_TRUE(cal);
      AssemblerOptions options;
      options.model = model;
      auto a = FrameAssembler::create(*cal, options);
      ASSERT_TRUE(a) << a.error().message;
      std::vector<sim::LidarPoint> span(frame_capacity(model, returns));
      a->set_output(span);
      std::vector<CompletedFrame> frames;
      std::int64_t host = 0;
      for (const auto& p : synthetic_turns(model, returns, 3.5)) {
        const PushResult r = a->push(p, host += 1000);
        ASSERT_EQ(r.error, PacketError::none) << to_string(r.error);
        if (r.frame) {
          frames.push_back(*r.frame);
          a->set_output(span);
        }
      }
      // Turns 1 and 2 are whole (turn 0 is where the assembler joined, turn 3 never ends).
      ASSERT_EQ(frames.size(), 2u);
      EXPECT_EQ(a->counters().lost_packets, 0u);
      const std::size_t firings = 36000 / m.azimuth_step_10hz;
      for (const auto& f : frames) {
        EXPECT_TRUE(f.whole);
        // Every channel of every firing, once: a dual-return pair of identical returns keeps
        // only its last.
        EXPECT_EQ(f.point_count, firings * m.channels);
        EXPECT_EQ(f.lost_packets, 0u);
      }
      EXPECT_NEAR(static_cast<double>(frames[1].stamp_ns - frames[0].stamp_ns), 100e6, 1e3);
    }
  }
}
