// SPDX-License-Identifier: Apache-2.0
// Decode throughput of sim::hesai::FrameAssembler on the real captures, on one core:
// UDP payloads in memory → points in a caller's span, frames swapped as a driver swaps loans.
// Counters: points/s, and x_real_time = seconds of sensor data decoded per second (the
// issue's target is ≥ 50× for the Pandar64). Side by side, in the same run: cutting by block
// azimuth (no per-point revolution test) and a memcpy of the payloads as a floor.
//
//   build-*/bench/hesai/bench_hesai_decode --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "pcap_payloads.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;

namespace {

struct Capture {
  std::vector<hesai_test::UdpPayload> packets;
  Calibration calibration;
  Model model;
  double sensor_seconds;  // how long the sensor took to send these packets
};

Capture load(const char* pcap, const char* csv, Model model) {
  auto packets = hesai_test::read_udp_payloads(hesai_test::data_path(pcap));
  auto cal = Calibration::load(hesai_test::data_path(csv), model);
  if (!cal || packets.size() < 2) throw std::runtime_error("cannot load the capture");
  Packet first, last;
  if (Packet::parse(packets.front().bytes, model, first) != PacketError::none ||
      Packet::parse(packets.back().bytes, model, last) != PacketError::none) {
    throw std::runtime_error("capture does not decode");
  }
  const double n = static_cast<double>(packets.size());
  const double seconds = static_cast<double>(last.time_ns() - first.time_ns()) * 1e-9 * n / (n - 1);
  return Capture{std::move(packets), std::move(*cal), model, seconds};
}

const Capture& pandar64() {
  static const Capture c = load("pandar64_dual.pcap", "pandar64.calibration.csv", Model::pandar64);
  return c;
}
const Capture& xt32() {
  static const Capture c =
      load("pandarxt32_dual.pcap", "pandarxt32.calibration.csv", Model::pandar_xt32);
  return c;
}

void decode(benchmark::State& state, const Capture& capture, CutBy cut_by) {
  AssemblerOptions options;
  options.model = capture.model;
  options.cut_by = cut_by;
  auto assembler = FrameAssembler::create(capture.calibration, options);
  if (!assembler) {
    state.SkipWithError(assembler.error().message.c_str());
    return;
  }
  // Two slots, as the SIM writer's double buffer gives.
  std::vector<sim::LidarPoint> slots[2] = {
      std::vector<sim::LidarPoint>(frame_capacity(capture.model, 2)),
      std::vector<sim::LidarPoint>(frame_capacity(capture.model, 2))};
  // Points decoded per pass over the capture, partial revolutions at both ends included (the
  // timed loop decodes them too, then drops the partial frames).
  std::uint64_t points_per_pass = 0;
  {
    AssemblerOptions all = options;
    all.emit_partial_frames = true;
    auto counting = FrameAssembler::create(capture.calibration, all);
    counting->set_output(slots[0]);
    for (const auto& p : capture.packets) {
      if (auto f = counting->push(p.bytes, p.capture_ns).frame) {
        points_per_pass += f->point_count;
        counting->set_output(slots[0]);
      }
    }
    if (auto f = counting->flush()) points_per_pass += f->point_count;
  }
  int slot = 0;
  assembler->set_output(slots[slot]);
  for (auto _ : state) {
    for (const auto& p : capture.packets) {
      if (assembler->push(p.bytes, p.capture_ns).frame) {
        slot ^= 1;
        assembler->set_output(slots[slot]);
      }
    }
    assembler->reset();  // the capture loops, as sim_replay_pcap --loop does
    benchmark::DoNotOptimize(slots[slot].data());
  }
  state.counters["points_per_s"] = benchmark::Counter(
      static_cast<double>(points_per_pass * state.iterations()), benchmark::Counter::kIsRate);
  state.counters["x_real_time"] = benchmark::Counter(
      capture.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["packets_per_s"] = benchmark::Counter(
      static_cast<double>(capture.packets.size() * state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Pandar64_PointCut(benchmark::State& s) { decode(s, pandar64(), CutBy::point_azimuth); }
void BM_Pandar64_BlockCut(benchmark::State& s) { decode(s, pandar64(), CutBy::block_azimuth); }
void BM_PandarXT32_PointCut(benchmark::State& s) { decode(s, xt32(), CutBy::point_azimuth); }

// The floor: copying the payload bytes once, with no decoding at all.
void BM_Pandar64_CopyPayloadsOnly(benchmark::State& state) {
  const Capture& capture = pandar64();
  std::vector<std::uint8_t> sink(2048);
  for (auto _ : state) {
    for (const auto& p : capture.packets) {
      std::memcpy(sink.data(), p.bytes.data(), p.bytes.size());
      benchmark::DoNotOptimize(sink.data());
    }
  }
  state.counters["x_real_time"] = benchmark::Counter(
      capture.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_Pandar64_PointCut)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pandar64_BlockCut)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PandarXT32_PointCut)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pandar64_CopyPayloadsOnly)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
