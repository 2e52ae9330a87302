// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: Ouster lidar and IMU payloads through the packet view and the frame
// assembler, under a metadata chosen by the first byte (profile, beams, columns per packet).
// Input: [selector] then records [u16 length little-endian][payload]. Nothing may read out of
// bounds, and a published frame never holds more points than its span.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "packet_encoder.hpp"
#include "sim/ouster/ouster.hpp"

namespace {

struct Setup {
  sim::ouster::Metadata metadata;
  std::vector<sim::LidarPoint> points;
};

const Setup& setup_for(std::uint8_t selector) {
  static std::vector<Setup> setups = [] {
    std::vector<Setup> all;
    using ouster_test::Layout;
    for (Layout l : {Layout::legacy, Layout::rng19, Layout::rng19_dual, Layout::rng15, Layout::fusa_dual}) {
      for (unsigned beams : {16u, 32u}) {
        auto m = sim::ouster::Metadata::parse(ouster_test::nested_metadata(l, beams, 1024, 16, 0));
        if (m) all.push_back({m.value(), {}});
      }
    }
    return all;
  }();
  return setups[selector % setups.size()];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const Setup& setup = setup_for(data[0]);
  sim::ouster::AssemblerOptions options;
  options.layout = (data[1] & 1) != 0 ? sim::ouster::CloudLayout::dense : sim::ouster::CloudLayout::organized;
  options.emit_partial_frames = (data[1] & 2) != 0;
  options.first_return_only = (data[1] & 4) != 0;
  auto assembler = sim::ouster::FrameAssembler::create(setup.metadata, options);
  if (!assembler) return 0;
  // A span smaller than a frame now and then: points beyond it are dropped, never written past.
  std::vector<sim::LidarPoint> points((data[1] & 8) != 0 ? 100 : assembler->max_points());
  assembler->set_output(points);
  std::size_t at = 2;
  while (at + 2 <= size) {
    const std::size_t length = std::min<std::size_t>(data[at] | std::size_t{data[at + 1]} << 8, size - at - 2);
    const std::span<const std::uint8_t> payload(data + at + 2, length);
    at += 2 + length;
    (void)sim::ouster::parse_imu(payload);
    (void)sim::ouster::guess_format(payload);
    const auto result = assembler->push(payload, 0);
    if (result.frame) {
      if (result.frame->point_count > points.size()) __builtin_trap();
      assembler->set_output(points);
    }
  }
  if (auto last = assembler->finish(); last && last->point_count > points.size()) __builtin_trap();
  return 0;
}
