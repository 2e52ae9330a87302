// SPDX-License-Identifier: Apache-2.0
// Writes the fuzz seed corpus (corpus/<kind>/*.cdr): small well-formed messages made by the
// encoder, so the fuzzers start from valid XCDR1. Rerun after a change of the wire format:
//   ros2_make_seeds tests/ros2/corpus
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/lidar_point.hpp"
#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/graph.hpp"
#include "sim/ros2/metadata.hpp"

namespace {

using namespace sim;
using namespace sim::ros2;

void save(const std::filesystem::path& dir, const std::string& name, const MessagePlan& plan,
          std::span<const std::byte> payload) {
  std::filesystem::create_directories(dir);
  std::vector<std::byte> out(plan.size());
  plan.write(payload, out);
  std::ofstream(dir / name, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

void save_bytes(const std::filesystem::path& dir, const std::string& name,
                const std::vector<std::byte>& out) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

std::vector<std::byte> bytes(std::size_t n) {
  std::vector<std::byte> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = std::byte(static_cast<unsigned char>(i * 13));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: ros2_make_seeds <corpus folder>\n");
    return 2;
  }
  const std::filesystem::path root = argv[1];
  const Header header{Time{1700000000, 5}, "sensor"};
  for (PixelFormat f : {PixelFormat::mono8, PixelFormat::mono16, PixelFormat::bgr8, PixelFormat::yuyv}) {
    const ImageLayout layout = ImageLayout::packed(4, 3, f);
    const auto pixels = bytes(layout.frame_bytes());
    save(root / "image", std::string(to_string(f)) + ".cdr", plan_image(layout, pixels.size(), header).value(),
         pixels);
  }
  const auto jpeg = bytes(40);
  save(root / "compressed_image", "jpeg.cdr", plan_compressed_image("jpeg", jpeg.size(), header).value(), jpeg);
  for (PointType t : {PointType::xyz32, PointType::xyzi32, PointType::lidar_point}) {
    const auto points = bytes(point_size(t) * 5);
    save(root / "point_cloud2", std::string(to_string(t)) + ".cdr",
         plan_point_cloud2(PointLayout::of(t, 5), points.size(), header).value(), points);
  }
  CameraCalibration calibration;
  calibration.width = 640;
  calibration.height = 480;
  calibration.d = {-0.1, 0.01, 0.0, 0.0, 0.001};
  calibration.k = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  calibration.p = {500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0};
  save_bytes(root / "camera_info", "plumb_bob.cdr", encode_camera_info(header, calibration).value());
  const TransformStamped transforms[] = {
      {{Time{1700000000, 5}, "base_link"}, "lidar_top", Mounting{{0.1, 0, 1.8}, {0, 0, 0, 1}}},
      {{Time{1700000000, 5}, "base_link"}, "camera_front", Mounting{{1.2, 0, 1.4}, {0.5, -0.5, 0.5, -0.5}}},
  };
  save_bytes(root / "tf_message", "two_mountings.cdr", encode_tf_message(transforms).value());
  const Gid participant{1, 15, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 0, 0, 1, 0xc1};
  const Gid reader{1, 15, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 0, 0, 2, 0x04};
  const Gid writer{1, 15, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 0, 0, 3, 0x03};
  const NodeEntities node{"/", "sim_dds_bridge", {&reader, 1}, {&writer, 1}};
  save_bytes(root / "participant_entities_info", "one_node.cdr",
             encode_participant_entities_info(participant, {&node, 1}));
  ClockStatus clock;
  clock.source = ClockSource::ptp;
  clock.state = ClockState::locked;
  clock.grandmaster = "00a069.fffe.0b552d";
  clock.offset_to_host_ns = 12'000;
  clock.verdict = ClockVerdict::ok;
  const DiagnosticArray diagnostics{Time{1700000000, 5}, "",
                                    {clock_diagnostic("/lidar_top", "SN1", clock, true),
                                     clock_diagnostic("/camera", "/camera", std::nullopt, true)}};
  save_bytes(root / "diagnostic_array", "two_clocks.cdr", encode_diagnostic_array(diagnostics).value());
  return 0;
}
