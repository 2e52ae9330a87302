// SPDX-License-Identifier: Apache-2.0
// Decode throughput of sim::hesai::FrameAssembler on the real captures (Pandar64, XT32, QT128,
// Pandar40P) and on synthetic revolutions of the models no capture exists of (XT16, QT64,
// XT32M, built from the layout tables as the tests build them), on one core:
// UDP payloads in memory → points in a caller's span, frames swapped as a driver swaps loans.
// Counters: points/s, and x_real_time = seconds of sensor data decoded per second (the
// target is ≥ 50× for every model, issue 17). Side by side, in the same run: cutting by block
// azimuth (no per-point revolution test) and a memcpy of the payloads as a floor.
//
//   build-*/bench/hesai/bench_hesai_decode --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true      (one line)
#include <benchmark/benchmark.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "packet_builder.hpp"
#include "hesai_test_data.hpp"
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

const Capture& qt128() {
  static const Capture c =
      load("pandarqt128_dual.pcap", "pandarqt128.calibration.csv", Model::pandar_qt128);
  return c;
}
const Capture& pandar40p() {
  static const Capture c = load("pandar40p_last_20hz_raw.pcapng",
                                "pandar40p.example-calibration.csv", Model::pandar40p);
  return c;
}

// Two revolutions at 10 Hz, dual return (last + strongest differing by 0.2–1 m, as real
// surfaces give), every channel returning, a calibration with ±1° azimuth offsets.
Capture synthetic(Model model) {
  const ModelInfo& m = info(model);
  constexpr unsigned returns = 2;
  const unsigned groups = m.blocks_per_packet / returns;
  const unsigned step = m.azimuth_step_10hz;
  const unsigned packets = 2 * 36000 / (step * groups);
  std::vector<ChannelAngles> angles;
  for (unsigned ch = 0; ch < m.channels; ++ch) {
    angles.push_back({15.0f - 30.0f * static_cast<float>(ch) / m.channels, ch % 2 ? 1.0f : -1.0f});
  }
  auto calibration = Calibration::from_angles(angles);
  Capture c{{}, std::move(calibration.value()), model, 0.2};
  for (unsigned k = 0; k < packets; ++k) {
    hesai_test::SyntheticPacket s;
    s.channels = m.channels;
    s.blocks = m.blocks_per_packet;
    s.returns = returns;
    s.return_mode = 0x39;
    s.first_azimuth = static_cast<std::uint16_t>((k * groups * step) % 36000);
    s.azimuth_step = static_cast<std::uint16_t>(step);
    const auto us = static_cast<std::uint64_t>(k) * 200000 / packets;
    s.utc[5] = static_cast<std::uint8_t>(7 + us / 1000000);
    s.micros = static_cast<std::uint32_t>(us % 1000000);
    s.sequence = k;
    s.distance = [k](unsigned block, unsigned ch) {
      return static_cast<std::uint16_t>(((ch * 7 + k) % 40 + 2) * 250 + (block % 2) * (50 + ch % 200));
    };
    auto bytes = model == Model::pandar_qt64 ? hesai_test::build_qt64(s) : hesai_test::build_xt(s);
    c.packets.push_back({static_cast<std::int64_t>(us) * 1000, 2368, std::move(bytes)});
  }
  return c;
}
const Capture& xt32m() {
  static const Capture c = synthetic(Model::pandar_xt32m);
  return c;
}
const Capture& xt16() {
  static const Capture c = synthetic(Model::pandar_xt16);
  return c;
}
const Capture& qt64() {
  static const Capture c = synthetic(Model::pandar_qt64);
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
    if (auto f = counting->finish()) points_per_pass += f->point_count;
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
void BM_PandarQT128_PointCut(benchmark::State& s) { decode(s, qt128(), CutBy::point_azimuth); }
void BM_Pandar40P_20Hz_PointCut(benchmark::State& s) { decode(s, pandar40p(), CutBy::point_azimuth); }
void BM_PandarXT32M_Synthetic(benchmark::State& s) { decode(s, xt32m(), CutBy::point_azimuth); }
void BM_PandarXT16_Synthetic(benchmark::State& s) { decode(s, xt16(), CutBy::point_azimuth); }
void BM_PandarQT64_Synthetic(benchmark::State& s) { decode(s, qt64(), CutBy::point_azimuth); }

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
BENCHMARK(BM_PandarQT128_PointCut)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pandar40P_20Hz_PointCut)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PandarXT32M_Synthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PandarXT16_Synthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PandarQT64_Synthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pandar64_CopyPayloadsOnly)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
