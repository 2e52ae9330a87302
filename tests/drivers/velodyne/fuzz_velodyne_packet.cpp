// SPDX-License-Identifier: Apache-2.0
// Fuzzes the packet parsers and the frame assembler with outside bytes. Input: [model index]
// [option flags] then records of [u16 length][payload]; the same bytes also go to the position
// packet parser (and its clock record) and model detection. Every completed frame must fit its span.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/velodyne/velodyne.hpp"

using namespace sim::velodyne;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const Model model = all_models[data[0] % all_models.size()];
  const std::uint8_t flags = data[1];
  data += 2;
  size -= 2;
  std::vector<LaserCorrection> lasers(info(model).lasers);
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    lasers[i].vert_correction = -0.3 + 0.005 * static_cast<double>(i);
    lasers[i].rot_correction = (flags & 1) ? 0.1 - 0.002 * static_cast<double>(i) : 0.0;
    if (flags & 2) {
      lasers[i].dist_correction = 1.2;
      lasers[i].dist_correction_x = 1.3;
      lasers[i].dist_correction_y = 1.1;
      lasers[i].vert_offset_correction = 0.2;
      lasers[i].horiz_offset_correction = 0.026;
      lasers[i].focal_slope = 1.0;
      lasers[i].focal_distance = 12;
    }
  }
  AssemblerOptions options;
  options.model = model;
  options.cut_azimuth_deg = (flags >> 4) * 22.5;
  options.emit_partial_frames = (flags & 4) != 0;
  options.interpolation = (flags & 8) ? AzimuthInterpolation::nebula : AzimuthInterpolation::firing_time;
  options.cut_by = (flags & 0x40) ? CutBy::packet : CutBy::point_azimuth;
  options.returns = static_cast<ReturnFilter>((flags >> 2) % 3);
  // A wrapping window, on the points or (nebula's VLP-32 decoder) on the blocks only.
  if ((flags & 0x80) != 0) options.azimuth_window = AssemblerOptions::AzimuthWindow{270, 90, false, (flags & 0x20) != 0};
  auto calibration = Calibration::from_lasers(lasers);
  if (!calibration) return 0;
  auto assembler = FrameAssembler::create(std::move(calibration.value()), options);
  if (!assembler) return 0;
  std::vector<sim::LidarPoint> span(4096);  // small on purpose: overflow must be counted
  assembler->set_output(span);
  std::int64_t host_ns = 1'700'000'000'000'000'000;
  while (size >= 2) {
    std::size_t length = static_cast<std::size_t>(data[0] | (data[1] << 8));
    data += 2;
    size -= 2;
    if (length > size) length = size;
    const std::span<const std::uint8_t> payload(data, length);
    (void)detect_model(payload);
    if (const auto report = parse_position_packet(payload, model)) {
      const sim::ClockStatus clock = clock_status_of(*report, host_ns);
      if (clock.problem.size() > sim::ClockStatus::kMaxProblem) __builtin_trap();
    }
    const PushResult r = assembler->push(payload, host_ns);
    if (r.frame) {
      if (r.frame->point_count > span.size()) __builtin_trap();
      assembler->set_output(span);
    }
    host_ns += 1'000'000;
    data += length;
    size -= length;
  }
  (void)assembler->finish();
  return 0;
}
