// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary UDP payloads through model detection, the packet validator and
// the frame assembler (both cut modes, any cut angle, spans that are too small, callers that
// forget set_output). Input: [model][flags] then records [length lo][length hi][payload…];
// the model byte indexes all_models (5 = PandarQT128, 6 = PandarXT32M).
// Invariants checked: no out-of-bounds access (ASan), frames never claim more points than the
// span holds, every point is finite.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;

namespace {

// Per model, a calibration with a spread of azimuth offsets like a real Pandar64 file, so
// points straddle the cut.
const Calibration& calibration_for(Model model) {
  static const std::vector<Calibration> all = [] {
    std::vector<Calibration> out;
    for (Model m : all_models) {
      std::vector<ChannelAngles> angles;
      for (unsigned ch = 0; ch < info(m).channels; ++ch) {
        const float offsets[] = {-5.208f, -1.042f, 1.042f, 5.208f, 0.0f};
        angles.push_back({15.0f - 40.0f * static_cast<float>(ch) / info(m).channels, offsets[ch % 5]});
      }
      auto calibration = Calibration::from_angles(angles);
      out.push_back(std::move(calibration.value()));
    }
    return out;
  }();
  return all[static_cast<std::size_t>(model)];
}

void check(const CompletedFrame& frame, std::span<const sim::LidarPoint> span) {
  if (frame.point_count > span.size()) __builtin_trap();
  for (std::size_t i = 0; i < frame.point_count; ++i) {
    const auto& p = span[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const Model model = all_models[data[0] % all_models.size()];
  const std::uint8_t flags = data[1];
  data += 2;
  size -= 2;

  AssemblerOptions options;
  options.model = model;
  options.cut_by = (flags & 1) ? CutBy::block_azimuth : CutBy::point_azimuth;
  constexpr double cuts[] = {0.0, 90.0, 180.0, 359.99};
  options.cut_azimuth_deg = cuts[(flags >> 1) & 3];
  options.emit_partial_frames = (flags & 8) != 0;
  options.drop_zero_distance = (flags & 16) == 0;
  if (flags & 16) options.min_range_m = 0.0f;
  const bool forget_output = (flags & 32) != 0;
  // Small enough to run fast, large enough to hold a partial revolution.
  const std::size_t span_size = (flags & 64) ? 300 : 40000;
  auto assembler = FrameAssembler::create(calibration_for(model), options);
  if (!assembler) __builtin_trap();

  // Allocated once: the fuzzer spends its time decoding, not zeroing buffers.
  static std::vector<sim::LidarPoint> a_storage(40000), b_storage(40000);
  const std::span<sim::LidarPoint> a(a_storage.data(), span_size), b(b_storage.data(), span_size);
  bool use_a = true;
  assembler->set_output(a);
  std::int64_t host_ns = 0;
  while (size >= 2) {
    std::size_t length = data[0] | (std::size_t{data[1]} << 8);
    data += 2;
    size -= 2;
    if (length > size) length = size;
    // An exact-size copy so ASan sees any read past the payload.
    const std::vector<std::uint8_t> payload(data, data + length);
    data += length;
    size -= length;

    (void)detect_model(payload);
    for (Model m : all_models) {
      Packet packet;
      if (Packet::parse(payload, m, packet) == PacketError::none) {
        (void)packet.firing_offset_ns(packet.blocks() - 1, packet.channels() - 1);
        if (packet.firing_loop(packet.blocks() - 1) > 1) __builtin_trap();
        if (const auto safety = packet.functional_safety()) {
          if (static_cast<unsigned>(safety->state) > 4) __builtin_trap();
        }
      }
    }
    const PushResult r = assembler->push(payload, host_ns += 1000);
    if (r.frame) {
      check(*r.frame, use_a ? std::span<const sim::LidarPoint>(a) : std::span<const sim::LidarPoint>(b));
      use_a = !use_a;
      if (!forget_output) assembler->set_output(use_a ? a : b);
    }
  }
  if (auto last = assembler->finish()) {
    check(*last, use_a ? std::span<const sim::LidarPoint>(a) : std::span<const sim::LidarPoint>(b));
  }
  return 0;
}
