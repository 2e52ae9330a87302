// SPDX-License-Identifier: Apache-2.0
// Models without a public capture (HDL-32E, HDL-64E, VLP-32C dual), position packets and bad
// input, through packets an independent encoder builds from the documented format
// (packet_builder.hpp). The expected points are computed here from the manuals' formulas in
// double precision, not by the decoder's code.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include "packet_builder.hpp"
#include "sim/velodyne/velodyne.hpp"

namespace {

using namespace sim::velodyne;
using velodyne_test::DataPacket;

constexpr std::int64_t hour_start_ns = 1'700'000'000'000'000'000 / 3'600'000'000'000 * 3'600'000'000'000;

Calibration load(const std::string& path) {
  auto c = Calibration::load(path);
  EXPECT_TRUE(c) << c.error().message;
  return std::move(c.value());
}
Calibration shipped(const std::string& name) { return load(std::string(VELODYNE_CALIBRATION_DIR) + "/" + name); }

// The distance every (sequence, laser) gets: varied, never zero.
std::uint16_t raw_distance(unsigned sequence, unsigned laser) {
  return static_cast<std::uint16_t>(2000 + (sequence * 37 + laser * 101) % 20000);
}

struct ExpectedPoint {
  double x, y, z;
  std::int64_t time_ns;
};

// Expected point from the documented model (ROS frame, azimuth rounded to 0.01° as documented).
ExpectedPoint expected_point(double distance_m, double azimuth_centi, double vert_rad, std::int64_t time_ns) {
  const double a = std::fmod(std::floor(azimuth_centi + 0.5) + 36000.0, 36000.0) / 100.0 * M_PI / 180.0;
  return {distance_m * std::cos(vert_rad) * std::cos(a), -distance_m * std::cos(vert_rad) * std::sin(a),
          distance_m * std::sin(vert_rad), time_ns};
}

struct Decoded {
  std::vector<std::vector<sim::LidarPoint>> frames;
  std::vector<CompletedFrame> info;
  AssemblerCounters counters;
};

Decoded run(FrameAssembler& assembler, const std::vector<std::vector<std::uint8_t>>& packets) {
  Decoded out;
  std::vector<sim::LidarPoint> span(400'000);
  assembler.set_output(span);
  for (const auto& p : packets) {
    const PushResult r = assembler.push(p, hour_start_ns + 1'000'000'000);
    if (!r.frame) continue;
    out.frames.emplace_back(span.begin(), span.begin() + static_cast<std::ptrdiff_t>(r.frame->point_count));
    out.info.push_back(*r.frame);
    assembler.set_output(span);
  }
  out.counters = assembler.counters();
  return out;
}

// HDL-32E: one sequence per block, 32 lasers 1.152 µs apart, 46.08 µs per sequence, 2 mm.
TEST(VelodyneSynthetic, Hdl32ePointsFollowTheManualsGeometryAndFiringTimes) {
  const Calibration cal = shipped("HDL32.yaml");
  constexpr unsigned step = 16;  // 0.16° per sequence
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned k = 0; k < 400; ++k) {
    DataPacket p;
    p.product_id = 0x21;
    p.timestamp_us = static_cast<std::uint32_t>(std::llround(1'000'000 + k * 552.96));
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned seq = k * 12 + b;
      p.blocks[b].azimuth = static_cast<std::uint16_t>((30000 + seq * step) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {raw_distance(seq, l), static_cast<std::uint8_t>(l)};
    }
    packets.push_back(p.bytes());
  }
  AssemblerOptions o;
  o.model = Model::hdl32e;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler) << assembler.error().message;
  const Decoded r = run(*assembler, packets);
  ASSERT_EQ(r.frames.size(), 1U);
  EXPECT_TRUE(r.info[0].whole);
  EXPECT_EQ(r.counters.lost_packets, 0U);
  // The frame starts with the first point at or past 0°; check every point against the model.
  const auto& frame = r.frames[0];
  EXPECT_EQ(frame.size(), 2250U * 32U);  // 360° / 0.16° sequences, every laser
  std::size_t i = 0;
  std::int64_t stamp = 0;
  for (unsigned seq = 0; seq < 400 * 12 && i < frame.size(); ++seq) {
    const unsigned k = seq / 12;
    const unsigned b = seq % 12;
    for (unsigned l = 0; l < 32; ++l) {
      const double block_az = (30000 + seq * step) % 36000;
      const double az = block_az + step * (l * 1.152 / 46.08) - cal[l].rot_correction * 18000 / M_PI;
      const double unwrapped = 30000 + seq * step + (az - block_az);
      if (unwrapped < 36000 || unwrapped >= 72000) continue;  // another revolution
      const std::int64_t t = hour_start_ns + std::llround(1'000'000 + k * 552.96) * 1000 +
                             std::int64_t{b} * 46'080 + std::int64_t{l} * 1'152;
      if (i == 0) stamp = t;
      const ExpectedPoint e = expected_point(raw_distance(seq, l) * 0.002 + cal[l].dist_correction, az,
                                        cal[l].vert_correction, t);
      const sim::LidarPoint& p = frame[i++];
      ASSERT_NEAR(p.x, e.x, 2e-4) << "sequence " << seq << " laser " << l;
      ASSERT_NEAR(p.y, e.y, 2e-4);
      ASSERT_NEAR(p.z, e.z, 2e-4);
      ASSERT_EQ(p.time_offset_ns, static_cast<std::uint32_t>(e.time_ns - stamp));
      ASSERT_EQ(p.ring, cal.ring(l));
      ASSERT_EQ(p.intensity, static_cast<float>(l));
    }
  }
  EXPECT_EQ(i, frame.size());
  EXPECT_EQ(r.info[0].stamp_ns, stamp);
}

// An HDL-32E with firmware before 2.2.20.0 (2016) leaves bytes 1204 (return mode) and 1205
// (product ID) at 0 (velodyne_decoder's unpack_16_32_beam); ros-drivers/velodyne decodes it.
TEST(VelodyneSynthetic, Hdl32eFirmwareBefore2_2_20WithoutProductIdDecodesAsHdl32eStrongestWhenChosen) {
  const Calibration cal = shipped("HDL32.yaml");
  std::vector<std::vector<std::uint8_t>> named, unnamed;
  for (unsigned k = 0; k < 400; ++k) {
    DataPacket p;
    p.product_id = 0x21;
    p.timestamp_us = static_cast<std::uint32_t>(std::llround(1'000'000 + k * 552.96));
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned seq = k * 12 + b;
      p.blocks[b].azimuth = static_cast<std::uint16_t>((30000 + seq * 16) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {raw_distance(seq, l), static_cast<std::uint8_t>(l)};
    }
    named.push_back(p.bytes());
    p.product_id = 0;
    p.return_mode = 0;
    unnamed.push_back(p.bytes());
  }
  EXPECT_FALSE(detect_model(unnamed[0])) << "it does not name itself: chosen, never guessed";
  EXPECT_TRUE(is_unnamed_hdl32e(unnamed[0]));
  EXPECT_FALSE(is_unnamed_hdl32e(named[0]));
  Packet packet;
  ASSERT_EQ(Packet::parse(unnamed[0], Model::hdl32e, packet), PacketError::none);
  EXPECT_EQ(packet.return_mode(), ReturnMode::strongest);
  EXPECT_EQ(Packet::parse(unnamed[0], Model::vlp16, packet), PacketError::wrong_model);
  AssemblerOptions o;
  o.model = Model::hdl32e;
  auto with_id = FrameAssembler::create(cal, o);
  auto without_id = FrameAssembler::create(cal, o);
  ASSERT_TRUE(with_id && without_id);
  const Decoded a = run(*with_id, named);
  const Decoded b = run(*without_id, unnamed);
  ASSERT_EQ(b.frames.size(), 1U);
  EXPECT_EQ(b.counters.malformed, 0U);
  ASSERT_EQ(a.frames[0].size(), b.frames[0].size());
  EXPECT_EQ(std::memcmp(a.frames[0].data(), b.frames[0].data(), a.frames[0].size() * sizeof(sim::LidarPoint)), 0);
}

// The full HDL-64E model of ros-drivers/velodyne, written out here in double precision.
ExpectedPoint hdl64e_point(const LaserCorrection& c, std::uint16_t raw, double azimuth_centi) {
  const double a = std::fmod(std::floor(azimuth_centi + 0.5) + 36000.0, 36000.0) / 100.0 * M_PI / 180.0;
  const double sin_a = std::sin(a), cos_a = std::cos(a);
  const double cv = std::cos(c.vert_correction), sv = std::sin(c.vert_correction);
  const double d = raw * 0.002 + c.dist_correction;
  const double vo = c.vert_offset_correction, ho = c.horiz_offset_correction;
  double xy = d * cv - vo * sv;
  const double xx = std::abs(xy * sin_a - ho * cos_a);
  const double yy = std::abs(xy * cos_a + ho * sin_a);
  const double dx = (c.dist_correction - c.dist_correction_x) * (xx - 2.4) / (25.04 - 2.4) + c.dist_correction_x - c.dist_correction;
  const double dy = (c.dist_correction - c.dist_correction_y) * (yy - 1.93) / (25.04 - 1.93) + c.dist_correction_y - c.dist_correction;
  xy = (d + dx) * cv - vo * sv;
  const double vx = xy * sin_a - ho * cos_a;
  xy = (d + dy) * cv - vo * sv;
  const double vy = xy * cos_a + ho * sin_a;
  return {vy, -vx, (d + dy) * sv + vo * cv, 0};
}

TEST(VelodyneSynthetic, Hdl64eFromItsDbXmlUsesOffsetsTwoPointCorrectionAndUpperLowerBlocks) {
  const Calibration cal = load(std::string(VELODYNE_TEST_DATA) + "/hdl64e_synthetic.db.xml");
  constexpr unsigned step = 17;
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned k = 0; k < 760; ++k) {
    DataPacket p;
    p.product_id = 0x33;  // the HDL-64E's rotating status byte: no product ID
    p.return_mode = 0x48;
    p.timestamp_us = 2'000'000 + k * 288;
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned firing = k * 6 + b / 2;
      p.blocks[b].flag = (b % 2) == 0 ? 0xEE : 0xDD;
      p.blocks[b].azimuth = static_cast<std::uint16_t>((firing * step) % 36000);
      for (unsigned u = 0; u < 32; ++u) p.blocks[b].units[u] = {raw_distance(firing, u + 32 * (b % 2)), 100};
    }
    packets.push_back(p.bytes());
  }
  ASSERT_EQ(detect_model(packets[0]), Model::hdl64e);
  AssemblerOptions o;
  o.model = Model::hdl64e;
  o.min_range_m = 0.1f;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler) << assembler.error().message;
  const Decoded r = run(*assembler, packets);
  ASSERT_GE(r.frames.size(), 1U);
  const auto& frame = r.frames[0];
  // Check every point that belongs to the revolution [0°, 360°) after the first wrap: the
  // decoder publishes them in firing order, upper block first.
  std::size_t i = 0;
  for (unsigned firing = 0; firing < 760 * 6 && i < frame.size(); ++firing) {
    for (unsigned laser = 0; laser < 64; ++laser) {
      const LaserCorrection& c = cal[laser];
      const double az = firing * step - c.rot_correction * 18000 / M_PI;  // no interpolation
      const double rounded = std::floor(az + 0.5);
      if (rounded < 36000 || rounded >= 72000) continue;
      const std::uint16_t raw = raw_distance(firing, laser);
      const ExpectedPoint e = hdl64e_point(c, raw, az);
      const sim::LidarPoint& p = frame[i++];
      ASSERT_NEAR(p.x, e.x, 5e-4) << "firing " << firing << " laser " << laser << " point " << i - 1 << " ring " << p.ring << " expected ring " << cal.ring(laser);
      ASSERT_NEAR(p.y, e.y, 5e-4);
      ASSERT_NEAR(p.z, e.z, 5e-4);
      // Intensity: focal model, clamped to the laser's limits.
      const double focal = 1 - c.focal_distance / 13100;
      const double scaled = 1 - raw / 65535.0;
      const double intensity = std::clamp(100 + c.focal_slope * std::abs(256 * focal * focal - 256 * scaled * scaled),
                                          c.min_intensity, c.max_intensity);
      ASSERT_NEAR(p.intensity, intensity, 1e-3);
      ASSERT_EQ(p.time_offset_ns % 48'000, 0U);  // every laser of a firing shares its time
    }
  }
  EXPECT_EQ(i, frame.size());
}

// HDL-64E S3 dual return test data: 0.4° per firing (900 firings per revolution), three firings
// of 48 µs per packet. The last return everywhere; a nearer strongest return on odd lasers only
// (even lasers had one return, which the sensor repeats in both blocks).
constexpr unsigned hdl64e_dual_step = 40;
constexpr unsigned hdl64e_dual_period_us = 144;
std::uint16_t hdl64e_last_raw(unsigned firing, unsigned laser) { return raw_distance(firing, laser); }
std::uint16_t hdl64e_strongest_raw(unsigned firing, unsigned laser) {
  const std::uint16_t last = hdl64e_last_raw(firing, laser);
  return laser % 2 == 1 ? static_cast<std::uint16_t>(last / 2) : last;
}
std::vector<std::vector<std::uint8_t>> hdl64e_dual_capture(unsigned packets) {
  std::vector<std::vector<std::uint8_t>> data;
  for (unsigned k = 0; k < packets; ++k) {
    std::array<std::uint16_t, 3> azimuths{};
    for (unsigned f = 0; f < 3; ++f) azimuths[f] = static_cast<std::uint16_t>(((k * 3 + f) * hdl64e_dual_step) % 36000);
    const auto unit = [&](unsigned f, unsigned laser, bool last) {
      const unsigned firing = k * 3 + f;
      return velodyne_test::Unit{last ? hdl64e_last_raw(firing, laser) : hdl64e_strongest_raw(firing, laser),
                                 static_cast<std::uint8_t>(last ? 10 : 200)};
    };
    data.push_back(velodyne_test::hdl64e_dual_packet(2'000'000 + k * hdl64e_dual_period_us, azimuths, unit).bytes());
  }
  return data;
}

// HDL-64E S3 dual return: its packets name no return mode; the block layout (four blocks of one
// firing's azimuth) says it. Every point is checked against the model, in the decoder's order.
TEST(VelodyneSynthetic, Hdl64eS3DualReturnPacketsGiveBothReturnsOfEachFiring) {
  const Calibration cal = load(std::string(VELODYNE_TEST_DATA) + "/hdl64e_synthetic.db.xml");
  constexpr unsigned packets = 700;  // 2,100 firings, 2.3 revolutions
  constexpr unsigned step = hdl64e_dual_step;
  constexpr unsigned period_us = hdl64e_dual_period_us;
  const auto last_raw = hdl64e_last_raw;
  const auto strongest_raw = hdl64e_strongest_raw;
  const auto data = hdl64e_dual_capture(packets);
  ASSERT_EQ(detect_model(data[0]), Model::hdl64e);
  Packet parsed;
  ASSERT_EQ(Packet::parse(data[0], Model::hdl64e, parsed), PacketError::none);
  EXPECT_EQ(parsed.return_mode(), ReturnMode::dual);
  AssemblerOptions o;
  o.model = Model::hdl64e;
  o.min_range_m = 0.1f;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler) << assembler.error().message;
  const Decoded r = run(*assembler, data);
  ASSERT_GE(r.frames.size(), 1U);
  EXPECT_EQ(r.counters.lost_packets, 0U);
  const auto& frame = r.frames[0];
  // The revolution [0°, 360°) after the first wrap, block by block: strongest (only where it
  // differs), then last; both returns of a firing at the firing's time.
  std::size_t i = 0;
  std::int64_t stamp = -1;
  for (unsigned firing = 0; firing < packets * 3 && i < frame.size(); ++firing) {
    const std::int64_t t = std::int64_t{2'000'000 + firing / 3 * period_us} * 1000 + (firing % 3) * 48'000;
    for (unsigned block = 0; block < 4; ++block) {
      const bool last = block >= 2;
      for (unsigned u = 0; u < 32; ++u) {
        const unsigned laser = (block % 2) * 32 + u;
        const std::uint16_t raw = last ? last_raw(firing, laser) : strongest_raw(firing, laser);
        if (!last && raw == last_raw(firing, laser)) continue;
        const LaserCorrection& c = cal[laser];
        const double az = firing * step - c.rot_correction * 18000 / M_PI;
        const double rounded = std::floor(az + 0.5);
        if (rounded < 36000 || rounded >= 72000) continue;
        if (stamp < 0) stamp = t;
        const ExpectedPoint e = hdl64e_point(c, raw, az);
        const sim::LidarPoint& p = frame[i++];
        ASSERT_NEAR(p.x, e.x, 5e-4) << "firing " << firing << " block " << block << " laser " << laser;
        ASSERT_NEAR(p.y, e.y, 5e-4);
        ASSERT_NEAR(p.z, e.z, 5e-4);
        ASSERT_EQ(p.return_index, last ? 0 : 1);
        ASSERT_EQ(p.ring, cal.ring(laser));
        ASSERT_EQ(p.time_offset_ns, static_cast<std::uint32_t>(t - stamp));
      }
    }
  }
  EXPECT_EQ(i, frame.size());
  const auto count = [](const std::vector<sim::LidarPoint>& points, unsigned index) {
    return std::count_if(points.begin(), points.end(), [&](const auto& p) { return p.return_index == index; });
  };
  // The return filters keep one block of each upper and lower pair: 64 points per firing.
  for (const ReturnFilter filter : {ReturnFilter::last, ReturnFilter::strongest}) {
    o.returns = filter;
    auto filtered = FrameAssembler::create(cal, o);
    ASSERT_TRUE(filtered);
    const Decoded f = run(*filtered, data);
    ASSERT_GE(f.frames.size(), 1U);
    const unsigned index = filter == ReturnFilter::last ? 0 : 1;
    EXPECT_EQ(count(f.frames[0], index), static_cast<std::ptrdiff_t>(f.frames[0].size()));
    EXPECT_EQ(f.frames[0].size(), static_cast<std::size_t>(count(frame, 0)));
  }
}

// 700 VLP-32C dual-return packets (more than two revolutions, 0.2° a sequence): each packet's
// six pairs of blocks (last return, then strongest) hold unit(sequence, pair, half, laser).
template <typename UnitOf>
std::vector<std::vector<std::uint8_t>> vlp32c_dual_packets(UnitOf unit) {
  constexpr unsigned step = 20;
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned k = 0; k < 700; ++k) {
    DataPacket p;
    p.product_id = 0x28;
    p.return_mode = 0x39;
    p.timestamp_us = static_cast<std::uint32_t>(std::llround(3'000'000 + k * 331.776));
    for (unsigned pair = 0; pair < 6; ++pair) {
      const unsigned seq = k * 6 + pair;
      for (unsigned half = 0; half < 2; ++half) {
        auto& block = p.blocks[pair * 2 + half];
        block.azimuth = static_cast<std::uint16_t>((seq * step) % 36000);
        for (unsigned l = 0; l < 32; ++l) block.units[l] = unit(seq, pair, half, l);
      }
    }
    packets.push_back(p.bytes());
  }
  return packets;
}

TEST(VelodyneSynthetic, Vlp32cDualKeepsTheSecondReturnOnlyWhereItDiffers) {
  const Calibration cal = shipped("VLP32.yaml");
  const auto packets = vlp32c_dual_packets([](unsigned seq, unsigned, unsigned half, unsigned l) {
    const std::uint16_t last = raw_distance(seq, l);
    // Odd lasers see a second, nearer and stronger return; even lasers one return only.
    const std::uint16_t strongest = (l % 2 == 1 && half == 1) ? static_cast<std::uint16_t>(last / 2) : last;
    return velodyne_test::Unit{half == 0 ? last : strongest, static_cast<std::uint8_t>(half == 0 ? 10 : 200)};
  });
  AssemblerOptions o;
  o.model = Model::vlp32c;
  o.min_range_m = 0.1f;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler);
  const Decoded r = run(*assembler, packets);
  ASSERT_GE(r.frames.size(), 1U);
  const auto& frame = r.frames[0];
  std::size_t firsts = 0, seconds = 0;
  for (const auto& p : frame) (p.return_index == 0 ? firsts : seconds)++;
  EXPECT_EQ(firsts, 1800U * 32U);   // 360° / 0.2°, every laser
  EXPECT_EQ(seconds, 1800U * 16U);  // only the odd lasers' differing returns
  // A pair's two returns share their firing time: ((laser / 2) · 2.304 µs into the sequence).
  for (std::size_t i = 0; i + 1 < frame.size(); ++i) {
    if (frame[i + 1].return_index == 1 && frame[i].return_index == 0 && frame[i].ring == frame[i + 1].ring) {
      EXPECT_EQ(frame[i].time_offset_ns, frame[i + 1].time_offset_ns);
    }
  }

  // Return filters: only last, only strongest.
  for (const ReturnFilter filter : {ReturnFilter::last, ReturnFilter::strongest}) {
    o.returns = filter;
    auto filtered = FrameAssembler::create(cal, o);
    ASSERT_TRUE(filtered);
    const Decoded f = run(*filtered, packets);
    ASSERT_GE(f.frames.size(), 1U);
    EXPECT_EQ(f.frames[0].size(), 1800U * 32U);
    for (const auto& p : f.frames[0]) EXPECT_EQ(p.return_index, filter == ReturnFilter::last ? 0 : 1);
  }
}

// The decoder skips the arithmetic of a block none of whose units is a point (a strongest-return
// block that repeats its pair in every unit, a block of sky): such blocks must add nothing, and
// the blocks after them must still decode, in every packet of the revolution.
TEST(VelodyneSynthetic, Vlp32cDualBlocksRepeatingTheirPairAddNoPointsAndTheNextBlocksStillDecode) {
  const Calibration cal = shipped("VLP32.yaml");
  constexpr unsigned differing_laser = 5;
  // Even pairs: the strongest block repeats the last one exactly; odd pairs: one laser differs.
  // The last pair of every packet is sky (no return at all) in its strongest block.
  const auto packets = vlp32c_dual_packets([](unsigned seq, unsigned pair, unsigned half, unsigned l) {
    const std::uint16_t last = raw_distance(seq, l);
    const bool differs = half == 1 && pair % 2 == 1 && l == differing_laser;
    const bool sky = half == 1 && pair == 5;
    return velodyne_test::Unit{sky ? std::uint16_t{0} : differs ? static_cast<std::uint16_t>(last / 2) : last, 7};
  });
  AssemblerOptions o;
  o.model = Model::vlp32c;
  o.min_range_m = 0.1f;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler);
  const Decoded r = run(*assembler, packets);
  ASSERT_GE(r.frames.size(), 1U);
  std::size_t firsts = 0, seconds = 0;
  for (const auto& p : r.frames[0]) {
    if (p.return_index == 0) {
      ++firsts;
      continue;
    }
    ++seconds;
    EXPECT_EQ(p.ring, cal.ring(differing_laser));
  }
  EXPECT_EQ(firsts, 1800U * 32U);  // 360° / 0.2°, every laser's last return
  EXPECT_EQ(seconds, 2U * (1800U / 6U));  // pairs 1 and 3 of each of a revolution's 300 packets
}

// VLP-32C single return, 0.2° a sequence: the default decodes by the manual's firing table (the
// lasers fire in pairs, 2.304 µs apart), the nebula mode by nebula's VLP-32 decoder (unit j one
// 2.304 µs slot after unit j − 1, of the difference to the next block; the packet's last block
// none). Expected points come from those two rules here, in double; a point must lie within
// 0.005° (the 0.01° rounding) of its rule's azimuth, where the rules differ by up to 0.13°.
struct Vlp32cExpectation {
  double azimuth_centi;  // before rounding
  unsigned seq;
  unsigned laser;
  std::int64_t time_ns;
};

std::vector<std::vector<std::uint8_t>> vlp32c_single_packets(unsigned packets, unsigned step) {
  std::vector<std::vector<std::uint8_t>> out;
  for (unsigned k = 0; k < packets; ++k) {
    DataPacket p;
    p.product_id = 0x28;
    p.timestamp_us = static_cast<std::uint32_t>(std::llround(2'000'000 + k * 663.552));
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned seq = k * 12 + b;
      p.blocks[b].azimuth = static_cast<std::uint16_t>((30000 + seq * step) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {raw_distance(seq, l), 9};
    }
    out.push_back(p.bytes());
  }
  return out;
}

// The first whole revolution's points in order, as the rule `offset(block, laser)` (0.01°
// past the block's azimuth, before rot_correction) puts them.
template <typename Offset>
std::vector<Vlp32cExpectation> vlp32c_expected(const Calibration& cal, unsigned packets, unsigned step, Offset offset) {
  std::vector<Vlp32cExpectation> out;
  for (unsigned seq = 0; seq < packets * 12; ++seq) {
    for (unsigned l = 0; l < 32; ++l) {
      const double az = 30000 + seq * step + offset(seq % 12, l) - cal[l].rot_correction * 18000 / M_PI;
      const double rounded = std::floor(az + 0.5);  // the revolution the decoder files it in
      if (rounded < 36000 || rounded >= 72000) continue;
      const std::int64_t t = hour_start_ns + std::llround(2'000'000 + (seq / 12) * 663.552) * 1000 +
                             std::int64_t{seq % 12} * 55'296 + std::int64_t{l / 2} * 2'304;
      out.push_back({az, seq, l, t});
    }
  }
  return out;
}

// The largest azimuth error (degrees) of the frame's points against the expectation, which
// must list the same points in the same order; time offsets and distances must match too.
double vlp32c_largest_error(const Calibration& cal, const std::vector<sim::LidarPoint>& frame,
                            const std::vector<Vlp32cExpectation>& expected) {
  EXPECT_EQ(frame.size(), expected.size());
  double largest = 0;
  for (std::size_t i = 0; i < frame.size() && i < expected.size(); ++i) {
    const sim::LidarPoint& p = frame[i];
    const Vlp32cExpectation& e = expected[i];
    EXPECT_EQ(p.ring, cal.ring(e.laser)) << "point " << i;
    EXPECT_EQ(p.time_offset_ns, static_cast<std::uint32_t>(e.time_ns - expected[0].time_ns)) << "point " << i;
    const double az = std::atan2(-p.y, p.x) * 18000 / M_PI;
    const double error = std::remainder(az - e.azimuth_centi, 36000.0) / 100.0;
    largest = std::max(largest, std::abs(error));
    EXPECT_NEAR(std::atan2(p.z, std::hypot(p.x, p.y)), cal[e.laser].vert_correction, 1e-5) << "point " << i;
  }
  return largest;
}

TEST(VelodyneSynthetic, Vlp32cLasersFireInPairsByDefaultAndOneAfterAnotherInTheNebulaMode) {
  const Calibration cal = shipped("VLP32.yaml");
  constexpr unsigned packets = 400;
  constexpr unsigned step = 20;
  const auto bytes = vlp32c_single_packets(packets, step);
  const auto pairs = [](unsigned, unsigned l) { return step * ((l / 2) * 2.304 / 55.296); };
  const auto slots = [](unsigned block, unsigned l) { return block == 11 ? 0.0 : step * (l * 2.304 / 55.296); };
  const auto manual = vlp32c_expected(cal, packets, step, pairs);
  const auto nebula = vlp32c_expected(cal, packets, step, slots);

  AssemblerOptions o;
  o.model = Model::vlp32c;
  auto by_manual = FrameAssembler::create(cal, o);
  ASSERT_TRUE(by_manual);
  const Decoded m = run(*by_manual, bytes);
  ASSERT_GE(m.frames.size(), 1U);
  EXPECT_LE(vlp32c_largest_error(cal, m.frames[0], manual), 0.0051);

  o.interpolation = AzimuthInterpolation::nebula;
  auto as_nebula = FrameAssembler::create(cal, o);
  ASSERT_TRUE(as_nebula);
  const Decoded n = run(*as_nebula, bytes);
  ASSERT_GE(n.frames.size(), 1U);
  EXPECT_LE(vlp32c_largest_error(cal, n.frames[0], nebula), 0.0051);
  // Within 0.005° of each rule, where the rules put most lasers more than 0.01° apart (laser 31:
  // 16 slots, 0.13°): each mode follows its own rule and not the other's.
  std::size_t apart = 0;
  double farthest = 0;
  for (const auto& e : manual) {
    const double d = std::abs(slots(e.seq % 12, e.laser) - pairs(e.seq % 12, e.laser)) / 100;
    apart += d > 0.0102 ? 1 : 0;
    farthest = std::max(farthest, d);
  }
  EXPECT_GT(apart, manual.size() * 3 / 4);
  EXPECT_NEAR(farthest, step * 16 * 2.304 / 55.296 / 100, 1e-9);
}

TEST(VelodyneSynthetic, TheCutAzimuthStartsEachFrameThere) {
  const Calibration cal = shipped("VLP16.yaml");
  std::vector<std::vector<std::uint8_t>> packets;
  for (unsigned k = 0; k < 400; ++k) {
    DataPacket p;
    p.timestamp_us = 5'000'000 + k * 1327;
    for (unsigned b = 0; b < 12; ++b) {
      p.blocks[b].azimuth = static_cast<std::uint16_t>(((k * 12 + b) * 40) % 36000);
      for (unsigned u = 0; u < 32; ++u) p.blocks[b].units[u] = {5000, 1};
    }
    packets.push_back(p.bytes());
  }
  AssemblerOptions o;
  o.cut_azimuth_deg = 90;
  auto assembler = FrameAssembler::create(cal, o);
  ASSERT_TRUE(assembler);
  const Decoded r = run(*assembler, packets);
  ASSERT_GE(r.frames.size(), 1U);
  for (const auto& frame : r.frames) {
    ASSERT_FALSE(frame.empty());
    // Velodyne azimuth 90° is −y in the ROS frame.
    const auto azimuth = [](const sim::LidarPoint& p) {
      const double a = std::atan2(-p.y, p.x) * 180 / M_PI;
      return a < 0 ? a + 360 : a;
    };
    EXPECT_NEAR(azimuth(frame.front()), 90.0, 0.05);
    EXPECT_GT(azimuth(frame.back()), 89.5);  // the last firing before 90°
    EXPECT_LT(azimuth(frame.back()), 90.0);
    EXPECT_EQ(frame.size(), 900U * 32U);  // 360° / 0.4° per block of two 16-laser sequences
  }
}

// VLS-128 dual return: a packet is one firing sequence (53.3 µs): every other packet missing is
// half of them lost, not none (the estimate once assumed 1.5 sequences per dual packet).
TEST(VelodyneSynthetic, Vls128DualPacketsLostAreCountedOneSequenceEach) {
  const Calibration cal = shipped("VLS128.yaml");
  std::vector<std::vector<std::uint8_t>> all, every_other;
  for (unsigned k = 0; k < 600; ++k) {
    DataPacket p;
    p.product_id = 0xA1;
    p.return_mode = 0x39;  // dual
    p.timestamp_us = static_cast<std::uint32_t>(std::llround(1'000'000 + k * 53.3));
    for (unsigned b = 0; b < 8; ++b) {
      p.blocks[b].flag = std::array<std::uint8_t, 4>{0xEE, 0xDD, 0xCC, 0xBB}[(b / 2) % 4];
      p.blocks[b].azimuth = static_cast<std::uint16_t>((k * 19) % 36000);
      for (unsigned l = 0; l < 32; ++l) p.blocks[b].units[l] = {static_cast<std::uint16_t>(3000 + l), 10};
    }
    all.push_back(p.bytes());
    if (k % 2 == 0) every_other.push_back(p.bytes());
  }
  for (const bool half : {false, true}) {
    AssemblerOptions o;
    o.model = Model::vls128;
    auto assembler = FrameAssembler::create(cal, o);
    ASSERT_TRUE(assembler) << assembler.error().message;
    const Decoded r = run(*assembler, half ? every_other : all);
    EXPECT_EQ(r.counters.malformed, 0U);
    EXPECT_EQ(r.counters.lost_packets, half ? 299U : 0U);
  }
}

TEST(VelodyneSynthetic, BadPacketsAreCountedAndNeverMakeAFrame) {
  AssemblerOptions o;
  auto assembler = FrameAssembler::create(shipped("VLP16.yaml"), o);
  ASSERT_TRUE(assembler);
  std::vector<sim::LidarPoint> span(1000);
  assembler->set_output(span);
  DataPacket good;
  auto bytes = good.bytes();
  const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.begin() + 600);
  DataPacket vls = good;
  vls.product_id = 0xA1;
  DataPacket bad_flag = good;
  bad_flag.blocks[5].flag = 0x00;
  DataPacket bad_azimuth = good;
  bad_azimuth.blocks[3].azimuth = 36000;
  DataPacket bad_mode = good;
  bad_mode.return_mode = 0x20;
  const std::vector<std::uint8_t> hesai(1080, 0xEE);  // another vendor's datagram
  EXPECT_EQ(assembler->push(truncated, 1).error, PacketError::bad_size);
  EXPECT_EQ(assembler->push(vls.bytes(), 1).error, PacketError::wrong_model);
  EXPECT_EQ(assembler->push(bad_flag.bytes(), 1).error, PacketError::bad_flag);
  EXPECT_EQ(assembler->push(bad_azimuth.bytes(), 1).error, PacketError::bad_azimuth);
  EXPECT_EQ(assembler->push(bad_mode.bytes(), 1).error, PacketError::bad_return_mode);
  EXPECT_EQ(assembler->push(hesai, 1).error, PacketError::bad_size);
  EXPECT_EQ(assembler->counters().malformed, 5U);
  EXPECT_EQ(assembler->counters().wrong_model, 1U);
  EXPECT_EQ(assembler->counters().packets, 0U);
  EXPECT_EQ(assembler->pending_points(), 0U);
  EXPECT_STREQ(to_string(PacketError::bad_flag), "a block that does not start with the flag the model sends there");
  EXPECT_FALSE(detect_model(hesai));
  EXPECT_FALSE(detect_model(truncated));
  EXPECT_EQ(detect_model(vls.bytes()), Model::vls128);
}

TEST(VelodyneSynthetic, PositionPacketsReportPpsAndGprmc) {
  const auto sentence = velodyne_test::nmea("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W");
  auto report = parse_position_packet(velodyne_test::position_packet(1234, 2, sentence));
  ASSERT_TRUE(report);
  EXPECT_EQ(report->timestamp_us, 1234U);
  EXPECT_EQ(report->pps, PpsState::locked);
  EXPECT_TRUE(report->has_gprmc);
  EXPECT_TRUE(report->gprmc_valid);
  ASSERT_TRUE(report->gprmc_utc_s);
  EXPECT_EQ(*report->gprmc_utc_s, 764426119);  // 1994-03-23 12:35:19 UTC
  // No fix ('V'), a bad checksum, and an HDL-32E's packet, whose byte 202 is no PPS state.
  auto no_fix = parse_position_packet(velodyne_test::position_packet(
      0, 1, velodyne_test::nmea("GPRMC,123519,V,,,,,,,230394,,")));
  ASSERT_TRUE(no_fix);
  EXPECT_EQ(no_fix->pps, PpsState::synchronizing);
  EXPECT_TRUE(no_fix->has_gprmc);
  EXPECT_FALSE(no_fix->gprmc_valid);
  std::string corrupt = sentence;
  corrupt[10] = '9';
  const auto bad_checksum = parse_position_packet(velodyne_test::position_packet(0, 2, corrupt));
  EXPECT_FALSE(bad_checksum->has_gprmc);
  EXPECT_EQ(bad_checksum->nmea, NmeaStatus::unreadable);
  auto hdl = parse_position_packet(velodyne_test::position_packet(0, 2, sentence), Model::hdl32e);
  ASSERT_TRUE(hdl);
  EXPECT_EQ(hdl->pps, PpsState::unknown);
  EXPECT_FALSE(parse_position_packet(std::vector<std::uint8_t>(100, 0)));
}

// A real VLP-16 sends 512 bytes of UDP payload (554 is the Ethernet frame): its PPS byte counts.
TEST(VelodyneSynthetic, ThePpsStateIsReadFromTheSensorsRealPositionPacketSize) {
  for (const std::size_t size : {std::size_t{512}, std::size_t{554}}) {
    for (const Model model : {Model::vlp16, Model::vlp32c, Model::vls128}) {
      const auto report = parse_position_packet(velodyne_test::position_packet(0, 1, "", size), model);
      ASSERT_TRUE(report) << size;
      EXPECT_EQ(report->pps, PpsState::synchronizing) << size << " " << to_string(model);
      EXPECT_EQ(report->nmea, NmeaStatus::none);
    }
  }
  EXPECT_EQ(parse_position_packet(velodyne_test::position_packet(0, 2, ""), Model::hdl64e)->pps, PpsState::unknown);
}

TEST(VelodyneSynthetic, AGpggaSentenceGivesTheFixAndTheTimeOfDay) {
  const auto fix = parse_position_packet(velodyne_test::position_packet(
      0, 2, velodyne_test::nmea("GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,")));
  ASSERT_TRUE(fix);
  EXPECT_EQ(fix->nmea, NmeaStatus::fix);
  EXPECT_FALSE(fix->has_gprmc);
  EXPECT_EQ(fix->nmea_second_of_hour, 27 * 60 + 50);
  const auto no_fix = parse_position_packet(
      velodyne_test::position_packet(0, 2, velodyne_test::nmea("GNGGA,092750.000,,,,,0,0,,,M,,M,,")));
  EXPECT_EQ(no_fix->nmea, NmeaStatus::no_fix);
}

TEST(VelodyneSynthetic, GarbageInThePositionPacketIsAnUnreadableSentenceOrAnInvalidPpsByte) {
  std::vector<std::uint8_t> garbage(512);
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>(i * 37 + 11);
  garbage[202] = 0xC7;
  const auto report = parse_position_packet(garbage, Model::vlp16);
  ASSERT_TRUE(report);
  EXPECT_EQ(report->pps, PpsState::invalid);
  EXPECT_EQ(report->pps_byte, 0xC7);
  EXPECT_EQ(report->nmea, NmeaStatus::unreadable);
  EXPECT_FALSE(report->has_gprmc);
  // A sentence of 128 bytes without its NUL, a '$' alone, a checksum with no digits.
  EXPECT_EQ(parse_position_packet(velodyne_test::position_packet(0, 2, std::string(300, '$')))->nmea,
            NmeaStatus::unreadable);
  EXPECT_EQ(parse_position_packet(velodyne_test::position_packet(0, 2, "$"))->nmea, NmeaStatus::unreadable);
  EXPECT_EQ(parse_position_packet(velodyne_test::position_packet(0, 2, "$GPRMC*"))->nmea, NmeaStatus::unreadable);
  EXPECT_EQ(parse_position_packet(velodyne_test::position_packet(0, 2, velodyne_test::nmea("GPRMC")))->nmea,
            NmeaStatus::unreadable);
}

// The clock record of each PPS state: what a launch script reads from the stream.
TEST(VelodyneSynthetic, EachPpsStateBecomesTheClockStateItMeans) {
  const auto gprmc = velodyne_test::nmea("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W");
  const std::uint32_t in_step = (35 * 60 + 20) * 1'000'000U;  // 12:35:20, a second after the sentence
  struct Case {
    std::uint8_t pps;
    sim::ClockState state;
    bool warns;
  };
  for (const Case c : {Case{0, sim::ClockState::free_running, true}, Case{1, sim::ClockState::acquiring, true},
                       Case{2, sim::ClockState::locked, false}, Case{3, sim::ClockState::holdover, true}}) {
    const auto report = parse_position_packet(velodyne_test::position_packet(in_step, c.pps, gprmc), Model::vlp16);
    ASSERT_TRUE(report);
    const sim::ClockStatus clock = clock_status_of(*report, 1'700'000'000'123'000'000);
    EXPECT_EQ(clock.source, sim::ClockSource::pps_nmea);
    EXPECT_EQ(clock.state, c.state) << int{c.pps};
    EXPECT_EQ(clock.stamps, sim::StampClock::sensor);
    EXPECT_EQ(clock.reported_ns, 1'700'000'000'123'000'000);
    EXPECT_EQ(clock.verdict, c.warns ? sim::ClockVerdict::warn : sim::ClockVerdict::unknown) << clock.problem;
    EXPECT_EQ(clock.problem.empty(), !c.warns) << clock.problem;
    EXPECT_FALSE(clock.offset_to_host_ns);  // measured by the clock check, not reported
  }
  const auto absent = clock_status_of(*parse_position_packet(velodyne_test::position_packet(in_step, 0, gprmc)), 1);
  EXPECT_NE(absent.problem.find("up to 30 minutes off"), std::string::npos) << absent.problem;
}

TEST(VelodyneSynthetic, ABadPositionPacketReportsAWarningNotALock) {
  std::vector<std::uint8_t> packet = velodyne_test::position_packet(0, 9, "not NMEA at all");
  const auto invalid = clock_status_of(*parse_position_packet(packet, Model::vlp16), 1);
  EXPECT_EQ(invalid.state, sim::ClockState::unknown);
  EXPECT_EQ(invalid.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(invalid.problem.find("PPS byte is 9"), std::string::npos) << invalid.problem;
  EXPECT_LE(invalid.problem.size(), sim::ClockStatus::kMaxProblem);

  // PPS locked, but the sentence is garbage, missing, or without a fix: still a warning.
  for (const std::string& sentence : {std::string("$GPRMC,garbage*00"), std::string(),
                                      velodyne_test::nmea("GPRMC,123519,V,,,,,,,230394,,")}) {
    const auto clock = clock_status_of(*parse_position_packet(velodyne_test::position_packet(0, 2, sentence)), 1);
    EXPECT_EQ(clock.state, sim::ClockState::locked) << sentence;
    EXPECT_EQ(clock.verdict, sim::ClockVerdict::warn) << sentence;
    EXPECT_NE(clock.problem.find("NMEA"), std::string::npos) << clock.problem;
  }
}

// With PPS locked the counter's minutes and seconds are the NMEA time's; a counter minutes away
// means stamps minutes off, which the hour fix against the host clock cannot see.
TEST(VelodyneSynthetic, ATopOfHourCounterThatDisagreesWithTheNmeaTimeIsAWarning) {
  const auto gprmc = velodyne_test::nmea("GPRMC,125959,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W");
  const auto agrees = clock_status_of(*parse_position_packet(velodyne_test::position_packet(0, 2, gprmc)), 1);
  EXPECT_EQ(agrees.verdict, sim::ClockVerdict::unknown) << agrees.problem;  // 59:59 → 00:00, across the hour
  const std::uint32_t ten_minutes_late = 10 * 60 * 1'000'000U;
  const auto late = clock_status_of(*parse_position_packet(velodyne_test::position_packet(ten_minutes_late, 2, gprmc)), 1);
  EXPECT_EQ(late.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(late.problem.find("is 601 s from its NMEA time"), std::string::npos) << late.problem;
}

TEST(VelodyneSynthetic, PacketTimeTakesTheHourNearestTheReference) {
  const std::int64_t hour = 3'600'000'000'000;
  const std::int64_t top = hour_start_ns;
  EXPECT_EQ(packet_time_ns(10, top + 5'000'000), top + 10'000);
  // Just after the top of the hour, a stamp from the end of the previous hour.
  EXPECT_EQ(packet_time_ns(3'599'999'000, top + 1'000'000), top - 1'000'000);
  // Just before the top of the hour, a stamp from the next one.
  EXPECT_EQ(packet_time_ns(1'000, top + hour - 1'000'000), top + hour + 1'000'000);
}

}  // namespace
