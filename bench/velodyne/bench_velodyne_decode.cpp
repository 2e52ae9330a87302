// SPDX-License-Identifier: Apache-2.0
// Decode throughput of sim::velodyne::FrameAssembler on one core, in the style of
// bench_hesai_decode: UDP payloads in memory → points in a caller's span, frames swapped as a
// driver swaps loans, the capture looped. Real captures: VLP-16 dual, VLS-128 strongest;
// synthetic revolutions (tests' packet_builder.hpp) for HDL-32E, VLP-32C dual, HDL-64E single and
// S3 dual (its db.xml: the full model with offsets and two-point correction), the Puck Hi-Res.
// x_real_time = seconds of sensor data decoded per second (target ≥ 50× for every model).
//
//   build-*/bench/velodyne/bench_velodyne_decode --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "velodyne/packet_builder.hpp"
#include "lidar_test/pcap_payloads.hpp"
#include "sim/velodyne/velodyne.hpp"

using namespace sim::velodyne;

namespace {

struct Capture {
  std::vector<std::vector<std::uint8_t>> packets;
  Calibration calibration;
  Model model;
  double sensor_seconds;  // how long the sensor took to send these packets
};

Calibration load_calibration(const std::string& path) {
  auto c = Calibration::load(path);
  if (!c) throw std::runtime_error(c.error().message);
  return std::move(c.value());
}

Capture real(const char* pcap, const char* yaml, Model model) {
  std::vector<std::vector<std::uint8_t>> packets;
  for (auto& p : lidar_test::read_udp_payloads(std::string(VELODYNE_TEST_DATA) + "/" + pcap)) {
    packets.push_back(std::move(p.bytes));
  }
  Packet first, last;
  if (packets.size() < 2 || Packet::parse(packets.front(), model, first) != PacketError::none ||
      Packet::parse(packets.back(), model, last) != PacketError::none) {
    throw std::runtime_error("capture does not decode");
  }
  const double n = static_cast<double>(packets.size());
  const double seconds = (last.timestamp_us() - first.timestamp_us()) * 1e-6 * n / (n - 1);
  return Capture{std::move(packets), load_calibration(std::string(VELODYNE_TEST_DATA) + "/" + yaml), model, seconds};
}

// Two revolutions at 10 Hz, every laser returning; dual: a second, nearer return on half the lasers.
Capture synthetic(Model model, const std::string& calibration, bool dual) {
  const ModelInfo& m = info(model);
  const unsigned pps = m.packets_per_second_single * (dual ? 2U : 1U);
  const unsigned packets = pps / 5;  // 0.2 s
  const unsigned slots_per_packet = 12 / m.blocks_per_sequence / (dual ? 2U : 1U);
  const double step = 36000.0 * 10 / (pps * slots_per_packet);  // 0.01° per slot at 10 Hz
  Capture c{{}, load_calibration(calibration), model, static_cast<double>(packets) / pps};
  for (unsigned k = 0; k < packets; ++k) {
    velodyne_test::DataPacket p;
    p.product_id = model == Model::hdl64e ? 0x00 : m.product_id;
    p.return_mode = dual ? 0x39 : 0x37;
    p.timestamp_us = static_cast<std::uint32_t>(k * 1e6 / pps);
    for (unsigned b = 0; b < 12; ++b) {
      const unsigned slot = k * slots_per_packet + b / (m.blocks_per_sequence * (dual ? 2U : 1U));
      p.blocks[b].azimuth = static_cast<std::uint16_t>(static_cast<unsigned>(slot * step) % 36000);
      p.blocks[b].flag = model == Model::hdl64e ? (b % 2 ? 0xDD : 0xEE)
                         : model == Model::vls128 ? static_cast<std::uint8_t>(0xEE - 0x11 * ((dual ? b / 2 : b) % 4))
                                                  : 0xEE;
      for (unsigned u = 0; u < 32; ++u) {
        const auto d = static_cast<std::uint16_t>(((u * 7 + k) % 40 + 2) * 250);
        const bool second = dual && b % 2 == 1 && u % 2 == 1;
        p.blocks[b].units[u] = {static_cast<std::uint16_t>(second ? d / 2 : d), 50};
      }
    }
    c.packets.push_back(p.bytes());
  }
  return c;
}

const std::string nominal = VELODYNE_CALIBRATION_DIR;

void decode(benchmark::State& state, const Capture& capture) {
  AssemblerOptions options;
  options.model = capture.model;
  auto assembler = FrameAssembler::create(capture.calibration, options);
  if (!assembler) {
    state.SkipWithError(assembler.error().message.c_str());
    return;
  }
  std::vector<sim::LidarPoint> slots[2] = {std::vector<sim::LidarPoint>(frame_capacity(capture.model, 2)),
                                           std::vector<sim::LidarPoint>(frame_capacity(capture.model, 2))};
  std::uint64_t points_per_pass = 0;
  {
    AssemblerOptions all = options;
    all.emit_partial_frames = true;
    auto counting = FrameAssembler::create(capture.calibration, all);
    counting->set_output(slots[0]);
    for (const auto& p : capture.packets) {
      if (auto f = counting->push(p, 1'700'000'000'000'000'000).frame) {
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
      if (assembler->push(p, 1'700'000'000'000'000'000).frame) {
        slot ^= 1;
        assembler->set_output(slots[slot]);
      }
    }
    assembler->reset();
    benchmark::DoNotOptimize(slots[slot].data());
  }
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(points_per_pass * state.iterations()), benchmark::Counter::kIsRate);
  state.counters["x_real_time"] =
      benchmark::Counter(capture.sensor_seconds * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void Vlp16Dual(benchmark::State& s) {
  static const Capture c = real("vlp16_dual.pcap", "VLP16.yaml", Model::vlp16);
  decode(s, c);
}
void Vls128Strongest(benchmark::State& s) {
  static const Capture c = real("vls128_strongest_first1100.pcap", "VLS128.yaml", Model::vls128);
  decode(s, c);
}
void Hdl32eSynthetic(benchmark::State& s) {
  static const Capture c = synthetic(Model::hdl32e, nominal + "/HDL32.yaml", false);
  decode(s, c);
}
void Vlp32cDualSynthetic(benchmark::State& s) {
  static const Capture c = synthetic(Model::vlp32c, nominal + "/VLP32.yaml", true);
  decode(s, c);
}
void PuckHiResSynthetic(benchmark::State& s) {
  static const Capture c = synthetic(Model::puck_hires, nominal + "/VLP16_hires.yaml", false);
  decode(s, c);
}
void Hdl64eSynthetic(benchmark::State& s) {
  static const Capture c =
      synthetic(Model::hdl64e, std::string(VELODYNE_TEST_DATA) + "/hdl64e_synthetic.db.xml", false);
  decode(s, c);
}
void Hdl64eDualSynthetic(benchmark::State& s) {
  // S3 dual return: four blocks per firing with one azimuth (the layout the decoder detects).
  static const Capture c =
      synthetic(Model::hdl64e, std::string(VELODYNE_TEST_DATA) + "/hdl64e_synthetic.db.xml", true);
  decode(s, c);
}
void Vls128DualSynthetic(benchmark::State& s) {
  static const Capture c = synthetic(Model::vls128, nominal + "/VLS128.yaml", true);
  decode(s, c);
}

}  // namespace

BENCHMARK(Vlp16Dual)->Unit(benchmark::kMillisecond);
BENCHMARK(Vls128Strongest)->Unit(benchmark::kMillisecond);
BENCHMARK(Hdl32eSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(Vlp32cDualSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(PuckHiResSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(Hdl64eSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(Hdl64eDualSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK(Vls128DualSynthetic)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
