// SPDX-License-Identifier: Apache-2.0
// What the clock checks cost the frame path (issue 30), side by side in one run: publish + read of
// one small frame per iteration in one process, with the checks off (no clock record, no check)
// and on (a driver's per-packet check, ClockCheck::add, for each of `packets` packets of the
// frame, a judgement written with Writer::set_clock once a second of frames at 10 Hz, i.e. every
// 10 frames here, far more often than a driver; the reader follows FrameInfo::clock_generation
// and reads Reader::clock() when it changes, and looks at FrameInfo::stamp_clock). Also the cost
// of ClockCheck::judge and Reader::clock() themselves, paid about once a second.
//
//   bench_clock_record [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "sim/sim.hpp"
#include "sim/timing/clock_check.hpp"

namespace {

constexpr int kPacketsPerFrame = 10;  // a 10 Hz LiDAR sends ~1000-3600 packets a second

struct Stream {
  std::string name;
  sim::Writer writer;
  sim::Reader reader;
  ~Stream() { (void)sim::destroy(name, true); }
};

Stream open_stream(const char* suffix) {
  const std::string name = "/bench_clock_record_" + std::to_string(getpid()) + suffix;
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = 64;
  auto writer = sim::Writer::create(spec);
  if (!writer) throw std::runtime_error(writer.error().message);
  auto reader = sim::Reader::open(name);
  if (!reader) throw std::runtime_error(reader.error().message);
  return Stream{name, std::move(*writer), std::move(*reader)};
}

sim::ClockStatus reported_ptp() {
  sim::ClockStatus c;
  c.source = sim::ClockSource::ptp;
  c.state = sim::ClockState::locked;
  c.grandmaster = "00a069.fffe.0b552d";
  c.stamps = sim::StampClock::sensor;
  return c;
}

// arg 0: checks off; arg 1: checks on.
void PublishAndRead(benchmark::State& state) {
  const bool checks = state.range(0) != 0;
  Stream s = open_stream(checks ? "_on" : "_off");
  sim::timing::ClockCheck check;
  const sim::ClockStatus reported = reported_ptp(), host{};
  std::vector<std::byte> frame(64, std::byte{1}), out(64);
  sim::FrameInfo info;
  std::uint64_t seen_generation = 0, frames = 0;
  std::int64_t stamp = sim::realtime_ns();
  for (auto _ : state) {
    stamp += 100'000'000;
    if (checks) {
      for (int p = 0; p < kPacketsPerFrame; ++p) check.add(stamp + p * 10'000, stamp + p * 10'000 + 20'000);
      if (++frames % 10 == 0 && !s.writer.set_clock(check.judge(reported, host, stamp))) {
        state.SkipWithError("the clock record was refused");
        break;
      }
    }
    if (s.writer.write(sim::span<const std::byte>(frame.data(), frame.size()), stamp) != sim::WriteStatus::ok ||
        s.reader.read(out.data(), out.size(), info) != sim::ReadStatus::new_frame) {
      state.SkipWithError("a frame was lost");
      break;
    }
    if (info.clock_generation != seen_generation) {
      seen_generation = info.clock_generation;
      auto clock = s.reader.clock();
      benchmark::DoNotOptimize(clock);
    }
    benchmark::DoNotOptimize(info.stamp_clock);
  }
  state.counters["clock_generation"] = static_cast<double>(seen_generation);
}
BENCHMARK(PublishAndRead)->Arg(0)->Arg(1)->ArgName("checks");

// ClockCheck::judge over a full window (paid about once a second, off the frame path).
void Judge(benchmark::State& state) {
  sim::timing::ClockCheck check;
  std::int64_t t = sim::realtime_ns();
  for (int i = 0; i < 20'000; ++i, t += 1'000'000) check.add(t, t + 20'000);
  const sim::ClockStatus reported = reported_ptp(), host{};
  for (auto _ : state) {
    auto judged = check.judge(reported, host, t);
    benchmark::DoNotOptimize(judged);
  }
}
BENCHMARK(Judge);

// Reader::clock(): copying and checking the record (paid when the generation changes).
void ClockCopy(benchmark::State& state) {
  Stream s = open_stream("_copy");
  if (!s.writer.set_clock(reported_ptp())) throw std::runtime_error("refused");
  for (auto _ : state) {
    auto clock = s.reader.clock();
    benchmark::DoNotOptimize(clock);
  }
}
BENCHMARK(ClockCopy);

}  // namespace

BENCHMARK_MAIN();
