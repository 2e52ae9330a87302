// SPDX-License-Identifier: Apache-2.0
// Decode throughput of sim::ouster::FrameAssembler on one core: lidar payloads in memory ->
// points in a caller's span (organised, destaggered, sensor frame), frames swapped as a driver
// swaps loans. The real captures (OS-1-32 LEGACY, OS-0-32 dual return; one frame each) and
// synthetic frames of the heaviest modes (128 beams × 2048 columns, dual and single; 128 × 1024
// dual, the OS-1-128's default mode; RNG15 low data rate), built with the tests' independent
// encoder. Counters: points/s and x_real_time = seconds of sensor data decoded per second
// (target ≥ 50×, issue 22). The *_memory_bound benchmarks do only the memory traffic a decoder
// cannot avoid (read every packet byte once, write every point byte once, with memcpy/memset) as
// the ceiling this machine puts on decoding; *_store_bound writes the points in the order a
// decoder of packets must (see store_bound), the lower ceiling of the organised layout.
//
//   build-*/bench/ouster/bench_ouster_decode --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "ouster_test_support.hpp"
#include "packet_encoder.hpp"
#include "sim/ouster/ouster.hpp"

using namespace sim::ouster;

namespace {

struct Input {
  Metadata metadata;
  std::vector<std::vector<std::uint8_t>> packets;  // whole frames
  double sensor_seconds;
};

Input real(const std::string& base) {
  auto capture = ouster_test::load_capture(base);
  const double seconds = static_cast<double>(capture.lidar.size()) * capture.metadata.format.columns_per_packet /
                         capture.metadata.columns() / capture.metadata.frequency_hz;
  return {capture.metadata, std::move(capture.lidar), seconds};
}

// Two frames of `layout`, every pixel returning (the worst case for the decoder).
Input synthetic(ouster_test::Layout layout, unsigned beams, unsigned columns) {
  auto m = Metadata::parse(ouster_test::nested_metadata(layout, beams, columns, 16, 1));
  if (!m) throw std::runtime_error(m.error().message);
  Input in{m.value(), {}, 2.0 / 10.0};
  for (std::uint32_t frame = 1; frame <= 2; ++frame) {
    for (unsigned first = 0; first < columns; first += 16) {
      ouster_test::PacketSpec s;
      s.layout = layout;
      s.beams = beams;
      s.frame_id = frame;
      s.init_id = 1;
      s.first_column = static_cast<std::uint16_t>(first);
      in.packets.push_back(ouster_test::encode_packet(s, [](unsigned v, unsigned u) {
        ouster_test::EncodedPixel p;
        p.range_mm = 1000 + 8 * ((v * 7 + u * 13) % 4000);
        p.range2_mm = p.range_mm + 800;
        p.reflectivity = static_cast<std::uint8_t>(u);
        p.signal = static_cast<std::uint16_t>(v);
        p.near_ir = static_cast<std::uint16_t>(16 * (u % 200));
        return p;
      }));
    }
  }
  return in;
}

void decode(benchmark::State& state, const Input& in, CloudLayout layout) {
  AssemblerOptions options;
  options.layout = layout;
  auto assembler = FrameAssembler::create(in.metadata, options).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  assembler.set_output(points);
  std::size_t decoded = 0;
  for (auto _ : state) {
    for (const auto& p : in.packets) {
      if (auto r = assembler.push(p, 0); r.frame) {
        decoded += r.frame->point_count;
        benchmark::DoNotOptimize(points.data());
        assembler.set_output(points);
      }
    }
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(decoded), benchmark::Counter::kIsRate);
  state.counters["x_real_time"] =
      benchmark::Counter(in.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// The bound: per frame, each packet copied into a packet-sized buffer (read once; the copy stays
// in L1) and the frame's points (H × W × returns × 24 bytes) written with memset.
void memory_bound(benchmark::State& state, const Input& in) {
  auto assembler = FrameAssembler::create(in.metadata, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  std::vector<std::uint8_t> packet(in.packets.front().size());
  const std::size_t frames = in.packets.size() * in.metadata.format.columns_per_packet / in.metadata.columns();
  const std::size_t packets_per_frame = in.packets.size() / frames;
  for (auto _ : state) {
    for (std::size_t f = 0; f < frames; ++f) {
      for (std::size_t i = 0; i < packets_per_frame; ++i) {
        const auto& p = in.packets[f * packets_per_frame + i];
        std::memcpy(packet.data(), p.data(), p.size());
        benchmark::DoNotOptimize(packet.data());
      }
      std::memset(static_cast<void*>(points.data()), 0, points.size() * sizeof(sim::LidarPoint));
      benchmark::DoNotOptimize(points.data());
      benchmark::ClobberMemory();
    }
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(points.size() * frames * state.iterations()),
                                                  benchmark::Counter::kIsRate);
  state.counters["x_real_time"] =
      benchmark::Counter(in.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// The bound of the organised layout's writes: per packet, the packet copied as above, then its
// columns' points written where the decoder writes them, with the decoder's prefetch (16 points
// in each beam's row of each return's image, destaggered: 256 rows 49 kB apart at 2048 columns
// dual), constant values, no arithmetic. Unlike memset's, these stores read each line before
// writing it, and 256 rows are more streams than the hardware prefetcher follows: this is the
// floor of any decoder that writes this layout packet by packet.
void store_bound(benchmark::State& state, const Input& in) {
  auto assembler = FrameAssembler::create(in.metadata, {}).value();
  std::vector<sim::LidarPoint> points(assembler.max_points());
  std::vector<std::uint8_t> packet(in.packets.front().size());
  const unsigned beams = in.metadata.beams(), width = in.metadata.columns();
  const unsigned per_packet = in.metadata.format.columns_per_packet;
  const std::size_t image = std::size_t{beams} * width;
  const unsigned returns = static_cast<unsigned>(points.size() / image);
  const sim::LidarPoint value{1, 2, 3, 4, 5, 6, 0, 0};
  for (auto _ : state) {
    for (std::size_t i = 0; i < in.packets.size(); ++i) {
      std::memcpy(packet.data(), in.packets[i].data(), in.packets[i].size());
      benchmark::DoNotOptimize(packet.data());
      const unsigned first = static_cast<unsigned>(i * per_packet % width);
      for (unsigned u = 0; u < beams; ++u) {
        const int shift = in.metadata.pixel_shift_by_row[u] % static_cast<int>(width);
        const unsigned start = (first + width + static_cast<unsigned>(shift)) % width;
        for (unsigned r = 0; r < returns; ++r) {
          sim::LidarPoint* row = points.data() + r * image + std::size_t{u} * width;
          unsigned column = start;
          for (unsigned k = 0; k < per_packet; ++k, column = column + 1 == width ? 0 : column + 1) row[column] = value;
          // The decoder's prefetch: the next packet's lines in this row (a point every 48 bytes
          // touches every line).
          for (unsigned k = 0; k < per_packet; k += 2, column = column + 2 >= width ? column + 2 - width : column + 2) {
            __builtin_prefetch(&row[column], 1);
          }
        }
      }
      benchmark::ClobberMemory();
    }
  }
  const double points_per_iteration = static_cast<double>(points.size() * in.packets.size() * per_packet / width);
  state.counters["points/s"] =
      benchmark::Counter(points_per_iteration * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["x_real_time"] =
      benchmark::Counter(in.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

const Input& input_128x2048_dual() {
  static const Input in = synthetic(ouster_test::Layout::rng19_dual, 128, 2048);
  return in;
}
const Input& input_128x2048_single() {
  static const Input in = synthetic(ouster_test::Layout::rng19, 128, 2048);
  return in;
}

void os1_32_legacy(benchmark::State& s) {
  static const Input in = real("OS-1-32-G_v2.1.1_1024x10");
  decode(s, in, CloudLayout::organized);
}
void os0_32_dual(benchmark::State& s) {
  static const Input in = real("OS-0-32-U1_v2.2.0_1024x10");
  decode(s, in, CloudLayout::organized);
}
void os0_32_dual_dense(benchmark::State& s) {
  static const Input in = real("OS-0-32-U1_v2.2.0_1024x10");
  decode(s, in, CloudLayout::dense);
}
void os_128x2048_dual(benchmark::State& s) { decode(s, input_128x2048_dual(), CloudLayout::organized); }
void os_128x2048_dual_memory_bound(benchmark::State& s) { memory_bound(s, input_128x2048_dual()); }
void os_128x2048_dual_store_bound(benchmark::State& s) { store_bound(s, input_128x2048_dual()); }
void os_128x2048_single(benchmark::State& s) { decode(s, input_128x2048_single(), CloudLayout::organized); }
void os_128x2048_single_memory_bound(benchmark::State& s) { memory_bound(s, input_128x2048_single()); }
// The OS-1-128's default lidar mode (1024×10) with dual return.
void os_128x1024_dual(benchmark::State& s) {
  static const Input in = synthetic(ouster_test::Layout::rng19_dual, 128, 1024);
  decode(s, in, CloudLayout::organized);
}
void os_128x1024_low_data_rate(benchmark::State& s) {
  static const Input in = synthetic(ouster_test::Layout::rng15, 128, 1024);
  decode(s, in, CloudLayout::organized);
}
void os_32x1024_fusa_dual(benchmark::State& s) {
  static const Input in = synthetic(ouster_test::Layout::fusa_dual, 32, 1024);
  decode(s, in, CloudLayout::organized);
}

}  // namespace

BENCHMARK(os1_32_legacy)->Unit(benchmark::kMicrosecond);
BENCHMARK(os0_32_dual)->Unit(benchmark::kMicrosecond);
BENCHMARK(os0_32_dual_dense)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x2048_dual)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x2048_dual_memory_bound)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x2048_dual_store_bound)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x2048_single)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x2048_single_memory_bound)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x1024_dual)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_128x1024_low_data_rate)->Unit(benchmark::kMicrosecond);
BENCHMARK(os_32x1024_fusa_dual)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
