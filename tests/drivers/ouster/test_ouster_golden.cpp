// SPDX-License-Identifier: Apache-2.0
// The Ouster decoder against real captures (data/, see data/NOTICE.md): every field of the first
// frame of both captures equals ouster-sdk's decoding (its MD5 digests), and every point equals
// the firmware manual's range-to-xyz formula, evaluated here independently in double precision
// from the metadata JSON (read with nlohmann, not with the driver's parser). One table of golden
// cases (capture and metadata, options, reference, tolerance) and parameterised tests over it,
// the shape every family's golden tests share (tests/support/lidar_test/golden.hpp).
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lidar_test/golden.hpp"
#include "ouster_test_support.hpp"
#include "sim/ouster/ouster.hpp"

namespace {

using namespace sim::ouster;
using lidar_test::Tolerance;
using ouster_test::Capture;
using ouster_test::load_capture;

// One golden case: a capture with its metadata (<base>.pcap, <base>.json), decoded with the
// default options, against ouster-sdk's digests of its first frame (<base>_digest.json, every
// field exact) and against the firmware manual's formula (every point within the tolerance).
struct GoldenCase {
  std::string name;
  std::string base;
  std::size_t lidar_packets;
  Tolerance formula_tolerance;
};

// Every point within 0.1 mm of the formula on each axis.
constexpr Tolerance formula_tolerance{Tolerance::Distance::largest_axis, 1e-4, 1.0};

const GoldenCase golden_cases[] = {
    {"LegacyOs1", "OS-1-32-G_v2.1.1_1024x10", 64, formula_tolerance},
    {"DualReturnOs0", "OS-0-32-U1_v2.2.0_1024x10", 64, formula_tolerance},
};

class OusterGoldenCase : public ::testing::TestWithParam<GoldenCase> {};

template <typename T>
std::string md5(const std::vector<T>& values) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(values.data(), values.size() * sizeof(T), digest, &length, EVP_md5(), nullptr);
  std::string hex;
  char byte[3];
  for (unsigned i = 0; i < length; ++i) {
    std::snprintf(byte, sizeof byte, "%02x", digest[i]);
    hex += byte;
  }
  return hex;
}

// Field images of the first frame, staggered (pixel (u, measurement_id)), as ouster-sdk keeps them.
struct Images {
  std::vector<std::uint32_t> range, range2;
  std::vector<std::uint16_t> signal, signal2, near_ir, measurement_id;
  std::vector<std::uint8_t> reflectivity, reflectivity2;
  std::vector<std::uint64_t> timestamp, status, encoder;
  std::uint32_t frame_id = 0;
};

Images first_frame_images(const Capture& capture) {
  const Metadata& m = capture.metadata;
  const std::size_t h = m.beams();
  const std::size_t w = m.columns();
  Images im;
  im.range.assign(h * w, 0);
  im.range2.assign(h * w, 0);
  im.signal.assign(h * w, 0);
  im.signal2.assign(h * w, 0);
  im.near_ir.assign(h * w, 0);
  im.reflectivity.assign(h * w, 0);
  im.reflectivity2.assign(h * w, 0);
  im.measurement_id.assign(w, 0);
  im.timestamp.assign(w, 0);
  im.status.assign(w, 0);
  im.encoder.assign(w, 0);
  bool first = true;
  for (const auto& payload : capture.lidar) {
    LidarPacket packet;
    EXPECT_EQ(LidarPacket::parse(payload, m.format, packet, m.init_id), PacketError::none);
    if (first) im.frame_id = packet.frame_id();
    first = false;
    if (packet.frame_id() != im.frame_id) break;
    for (unsigned c = 0; c < packet.columns(); ++c) {
      const Column col = packet.column(c);
      const std::size_t v = col.measurement_id;
      im.measurement_id[v] = col.measurement_id;
      im.timestamp[v] = col.timestamp_ns;
      im.status[v] = col.status;
      im.encoder[v] = col.encoder;
      for (std::size_t u = 0; u < h; ++u) {
        const Pixel px = packet.pixel(c, static_cast<unsigned>(u));
        const std::size_t i = u * w + v;
        im.range[i] = px.range_mm;
        im.range2[i] = px.range2_mm;
        im.signal[i] = px.signal;
        im.signal2[i] = px.signal2;
        im.near_ir[i] = px.near_ir;
        im.reflectivity[i] = px.reflectivity;
        im.reflectivity2[i] = px.reflectivity2;
      }
    }
  }
  return im;
}

TEST_P(OusterGoldenCase, EveryFieldOfTheFirstFrameEqualsOusterSdksDigest) {
  const std::string& base = GetParam().base;
  const Capture capture = load_capture(base);
  ASSERT_EQ(capture.lidar.size(), GetParam().lidar_packets);
  const Images im = first_frame_images(capture);
  const auto digest = nlohmann::json::parse(ouster_test::read_text(ouster_test::data_path(base + "_digest.json")));
  const auto& scan = digest.at("scans").at(0);
  std::map<std::string, std::string> ours = {
      {"RANGE", md5(im.range)},           {"RANGE2", md5(im.range2)},
      {"SIGNAL", md5(im.signal)},         {"SIGNAL2", md5(im.signal2)},
      {"NEAR_IR", md5(im.near_ir)},       {"REFLECTIVITY", md5(im.reflectivity)},
      {"REFLECTIVITY2", md5(im.reflectivity2)}, {"TIMESTAMP", md5(im.timestamp)},
      {"STATUS", md5(im.status)},         {"MEASUREMENT_ID", md5(im.measurement_id)},
      {"ENCODER_COUNT", md5(im.encoder)}, {"FRAME_ID", std::to_string(im.frame_id)}};
  unsigned checked = 0;
  for (const auto& [field, expected] : scan.items()) {
    ASSERT_TRUE(ours.count(field)) << "the reference has a field the test does not know: " << field;
    EXPECT_EQ(ours[field], expected.get<std::string>()) << base << " field " << field;
    ++checked;
  }
  EXPECT_GE(checked, 9u);
}

// The published formula, from the JSON directly: x = (r − n)·cos(θe+θa)·cos φ + n·cos θe, …,
// then lidar_to_sensor_transform (mm) to the sensor frame.
struct Expected {
  double x, y, z;
};
Expected formula(const nlohmann::json& meta, std::size_t u, std::size_t v, std::size_t w, double r) {
  const double pi = std::numbers::pi;
  const double n = meta.at("lidar_origin_to_beam_origin_mm").get<double>();
  const double theta_e = 2 * pi * (1 - static_cast<double>(v) / static_cast<double>(w));
  const double theta_a = -2 * pi * meta.at("beam_azimuth_angles").at(u).get<double>() / 360;
  const double phi = 2 * pi * meta.at("beam_altitude_angles").at(u).get<double>() / 360;
  const double lx = (r - n) * std::cos(theta_e + theta_a) * std::cos(phi) + n * std::cos(theta_e);
  const double ly = (r - n) * std::sin(theta_e + theta_a) * std::cos(phi) + n * std::sin(theta_e);
  const double lz = (r - n) * std::sin(phi);
  const auto& t = meta.at("lidar_to_sensor_transform");
  auto row = [&](int i) {
    return t.at(4 * i).get<double>() * lx + t.at(4 * i + 1).get<double>() * ly +
           t.at(4 * i + 2).get<double>() * lz + t.at(4 * i + 3).get<double>();
  };
  return {row(0) / 1000, row(1) / 1000, row(2) / 1000};
}

// Both returns where the profile has two; columns destaggered, with their column times.
TEST_P(OusterGoldenCase, PointsAreTheFormulasInTheSensorFrameDestaggeredWithColumnTimes) {
  const std::string& base = GetParam().base;
  const Capture capture = load_capture(base);
  const auto meta = nlohmann::json::parse(ouster_test::read_text(ouster_test::data_path(base + ".json")));
  const Images im = first_frame_images(capture);
  auto assembler = FrameAssembler::create(capture.metadata, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  assembler.set_output(points);
  std::optional<CompletedFrame> frame;
  for (const auto& payload : capture.lidar) {
    auto result = assembler.push(payload, 0);
    ASSERT_EQ(result.error, PacketError::none);
    if (result.frame) frame = result.frame;
  }
  ASSERT_TRUE(frame) << "the capture's last packet holds column 1023: the frame completes on it";
  EXPECT_TRUE(frame->whole);
  EXPECT_EQ(frame->missing_columns, 0u);
  const std::size_t h = capture.metadata.beams();
  const std::size_t w = capture.metadata.columns();
  const unsigned returns = returns_of(capture.metadata.format.profile);
  ASSERT_EQ(frame->point_count, h * w * returns);
  EXPECT_EQ(frame->stamp_ns, static_cast<std::int64_t>(im.timestamp[0]));
  const auto& shift = meta.at("data_format").at("pixel_shift_by_row");
  lidar_test::CloudComparison comparison(GetParam().formula_tolerance);
  std::size_t with_return = 0;
  for (unsigned ret = 0; ret < returns; ++ret) {
    for (std::size_t u = 0; u < h; ++u) {
      for (std::size_t v = 0; v < w; ++v) {
        // Destaggered: staggered column v of row u lands in column (v + shift[u]) mod W.
        const std::size_t column = (v + shift.at(u).get<std::size_t>()) % w;
        const sim::LidarPoint& p = points[ret * h * w + u * w + column];
        const std::uint32_t r = ret == 0 ? im.range[u * w + v] : im.range2[u * w + v];
        ASSERT_EQ(p.ring, u);
        ASSERT_EQ(p.return_index, ret);
        ASSERT_EQ(p.time_offset_ns, im.timestamp[v] - im.timestamp[0]);
        ASSERT_EQ(p.intensity, ret == 0 ? im.signal[u * w + v] : im.signal2[u * w + v]);
        if (r == 0) {
          ASSERT_EQ(p.x, 0.0F);
          ASSERT_EQ(p.y, 0.0F);
          ASSERT_EQ(p.z, 0.0F);
          continue;
        }
        ++with_return;
        comparison.add(p, formula(meta, u, v, w, r));
      }
    }
  }
  EXPECT_GT(with_return, h * w / 4) << "the captures see a scene";
  EXPECT_TRUE(comparison.holds()) << comparison.describe() << " (" << GetParam().formula_tolerance << ")";
}

INSTANTIATE_TEST_SUITE_P(Recorded, OusterGoldenCase, ::testing::ValuesIn(golden_cases), lidar_test::CaseName{});

TEST(OusterGolden, DenseCloudHoldsExactlyThePixelsWithAReturnInsideTheRangeLimits) {
  const Capture capture = load_capture("OS-0-32-U1_v2.2.0_1024x10");
  const Images im = first_frame_images(capture);
  AssemblerOptions options;
  options.layout = CloudLayout::dense;
  options.min_range_m = 1.0F;
  options.max_range_m = 50.0F;
  options.intensity = IntensityField::reflectivity;
  auto assembler = FrameAssembler::create(capture.metadata, options).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  assembler.set_output(points);
  std::optional<CompletedFrame> frame;
  for (const auto& payload : capture.lidar) {
    if (auto r = assembler.push(payload, 0); r.frame) frame = r.frame;
  }
  ASSERT_TRUE(frame);
  std::size_t expected = 0;
  std::size_t second = 0;
  for (std::size_t i = 0; i < im.range.size(); ++i) {
    expected += im.range[i] >= 1000 && im.range[i] <= 50000;
    second += im.range2[i] >= 1000 && im.range2[i] <= 50000;
  }
  EXPECT_EQ(frame->point_count, expected + second);
  std::size_t seen_second = 0;
  for (std::size_t i = 0; i < frame->point_count; ++i) {
    const auto& p = points[i];
    const double range = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    EXPECT_GT(range, 0.9);  // from the sensor origin; the returns' own range is 1–50 m
    seen_second += p.return_index == 1;
    EXPECT_LE(p.intensity, 255.0F);  // reflectivity
  }
  EXPECT_EQ(seen_second, second);
}

TEST(OusterGolden, TheImuPacketsOfTheOs0CaptureAreRead) {
  const Capture capture = load_capture("OS-0-32-U1_v2.2.0_1024x10");
  ASSERT_EQ(capture.imu.size(), 10u);
  for (const auto& payload : capture.imu) {
    auto imu = parse_imu(payload);
    ASSERT_TRUE(imu);
    const double g = std::sqrt(imu->acceleration_g[0] * imu->acceleration_g[0] +
                               imu->acceleration_g[1] * imu->acceleration_g[1] +
                               imu->acceleration_g[2] * imu->acceleration_g[2]);
    EXPECT_NEAR(g, 1.0, 0.1) << "a sensor at rest measures gravity";
    EXPECT_GT(imu->accel_ns, 0u);
  }
}

}  // namespace
