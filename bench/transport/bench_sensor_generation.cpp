// SPDX-License-Identifier: Apache-2.0
// What the sensor description costs a frame (issue 21): publish + read of one small frame in one
// process, on a stream without a description and on one with a camera's full description, side by
// side. Reading a frame of a described stream adds one load of a word in the header page
// (FrameInfo::sensor_generation): the two should not differ beyond noise. Also the cost of
// Reader::sensor_info() itself, which a consumer pays only when the generation changes.
//
//   bench_sensor_generation [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "sim/sim.hpp"

namespace {

sim::SensorInfo camera() {
  sim::SensorInfo info;
  info.frame_id = "camera_front_optical";
  info.mounting = sim::Mounting::from_xyz_rpy(1.5, 0.0, 1.2, -1.5707963267948966, 0.0, -1.5707963267948966);
  sim::CameraCalibration c;
  c.width = 1920;
  c.height = 1080;
  c.d = {-0.1, 0.01, 0.0, 0.0, 0.0};
  c.k = {1000, 0, 960, 0, 1000, 540, 0, 0, 1};
  c.p = {1000, 0, 960, 0, 0, 1000, 540, 0, 0, 0, 1, 0};
  info.calibration = c;
  info.identity = {"Basler", "acA1920", "40012345", "1.2.3"};
  return info;
}

struct Stream {
  std::string name;
  sim::Writer writer;
  sim::Reader reader;
  ~Stream() { (void)sim::destroy(name, true); }
};

Stream open_stream(bool described) {
  const std::string name = "/bench_sensor_generation_" + std::to_string(getpid()) + (described ? "_d" : "_n");
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = 64;
  if (described) spec.sensor = camera();
  auto writer = sim::Writer::create(spec);
  if (!writer) throw std::runtime_error(writer.error().message);
  auto reader = sim::Reader::open(name);
  if (!reader) throw std::runtime_error(reader.error().message);
  return Stream{name, std::move(*writer), std::move(*reader)};
}

// One frame published and read (copy) per iteration; arg 1: the stream has a description.
void PublishAndRead(benchmark::State& state) {
  Stream s = open_stream(state.range(0) != 0);
  std::vector<std::byte> frame(64, std::byte{1}), out(64);
  sim::FrameInfo info;
  std::uint64_t generations = 0;
  for (auto _ : state) {
    if (s.writer.write(sim::span<const std::byte>(frame.data(), frame.size()), 1) != sim::WriteStatus::ok ||
        s.reader.read(out.data(), out.size(), info) != sim::ReadStatus::new_frame) {
      state.SkipWithError("a frame was lost");
      break;
    }
    generations += info.sensor_generation;
    benchmark::DoNotOptimize(generations);
  }
  state.counters["generation"] = static_cast<double>(info.sensor_generation);
}
BENCHMARK(PublishAndRead)->Arg(0)->Arg(1)->ArgName("described");

// Reader::sensor_info(): copying and checking the whole description (not a per-frame cost).
void SensorInfoCopy(benchmark::State& state) {
  Stream s = open_stream(true);
  for (auto _ : state) {
    auto info = s.reader.sensor_info();
    benchmark::DoNotOptimize(info);
  }
}
BENCHMARK(SensorInfoCopy);

}  // namespace

BENCHMARK_MAIN();
