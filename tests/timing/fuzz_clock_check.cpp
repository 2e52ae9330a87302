// SPDX-License-Identifier: Apache-2.0
// Fuzzes the clock check with what a sensor can send: any sensor time against any arrival
// (INT64 extremes, backwards, far future), restarts, tolerances of any size, and any reported
// state. Input: records of 17 bytes: [op u8][sensor i64 LE][arrival i64 LE]; op's low bits:
// 0–5 a packet, 6 a restart, 7 a judgement (the record's numbers pick tolerances and states).
// Every judgement must be storable (sim::clock_status_problem finds nothing).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "sim/clock_status.hpp"
#include "sim/timing/clock_check.hpp"

namespace {

std::int64_t i64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  std::memcpy(&v, p, sizeof v);
  return static_cast<std::int64_t>(v);
}

void judge(sim::timing::ClockCheck& check, std::int64_t a, std::int64_t b) {
  sim::ClockStatus reported;
  sim::ClockStatus host;
  reported.state = static_cast<sim::ClockState>(static_cast<std::uint64_t>(a) % 5);
  reported.source = static_cast<sim::ClockSource>(static_cast<std::uint64_t>(b) % 8);
  reported.stamps = static_cast<sim::StampClock>((static_cast<std::uint64_t>(a) >> 8) % 4);
  host.state = static_cast<sim::ClockState>((static_cast<std::uint64_t>(b) >> 8) % 5);
  const sim::ClockStatus clock = check.judge(reported, host, b);
  if (!sim::clock_status_problem(clock).empty()) std::abort();
  if (clock.verdict != sim::ClockVerdict::ok && clock.verdict != sim::ClockVerdict::unknown &&
      clock.problem.empty()) {
    std::abort();  // a warning or an error always says why
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t record = 17;
  sim::timing::ClockTolerance tolerance;
  if (size >= record) {
    // The first record's numbers also set the tolerances: a user may set any.
    tolerance.offset_ok_ns = i64(data + 1) % 2'000'000'000;
    tolerance.step_ns = i64(data + 9) % 5'000'000'000;
    tolerance.future_ns = i64(data + 1) >> 3;
    tolerance.drift_warn_ppm = static_cast<double>(data[0]);
  }
  sim::timing::ClockCheck check(tolerance);
  for (std::size_t at = 0; at + record <= size; at += record) {
    const std::uint8_t op = data[at] & 7;
    const std::int64_t sensor = i64(data + at + 1);
    const std::int64_t arrival = i64(data + at + 9);
    if (op == 6) {
      check.restart();
    } else if (op == 7) {
      judge(check, sensor, arrival);
    } else {
      // A run of packets from this one: a sensor sends hundreds a second.
      // Wrapping steps (unsigned): a stamp may wrap past INT64_MAX like any garbage.
      const std::uint64_t step = (op & 1) ? 1'000'000u : std::uint64_t{0} - 1'000'000u;
      for (std::uint64_t i = 0; i <= op * 40u; ++i) {
        check.add(static_cast<std::int64_t>(static_cast<std::uint64_t>(sensor) + i * step),
                  static_cast<std::int64_t>(static_cast<std::uint64_t>(arrival) + i * 1'000'000u));
      }
    }
  }
  judge(check, static_cast<std::int64_t>(size), 0);
  return 0;
}
