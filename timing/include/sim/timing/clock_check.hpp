// SPDX-License-Identifier: Apache-2.0
// Checks a stream's clock by its data: each packet's own sensor time against that packet's
// arrival on this host (for a replay: the packet's capture time, the recording host's clock).
// Never a frame's stamp against the frame's completion: a frame takes a revolution to complete.
//
//   sim::timing::ClockCheck check;                  // one per stream
//   check.add(packet_sensor_ns, packet_arrival_ns); // per packet, on the receive path: cheap
//   writer.set_clock(check.judge(reported, host, sim::realtime_ns()));  // about once a second
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "sim/clock_status.hpp"

namespace sim::timing {

// What counts as fine, per stream (a camera's exposure and transfer time is not an error).
struct ClockTolerance {
  std::int64_t offset_ok_ns = 10'000'000;       // |median offset to host| up to this: ok
  std::int64_t offset_error_ns = 1'000'000'000; // beyond this: error (cannot be paired)
  std::int64_t spread_warn_ns = 5'000'000;      // a spread wider than this: warn
  std::int64_t step_ns = 500'000'000;           // a jump of the offset beyond this is a step
  double drift_warn_ppm = 50.0;                 // |drift| beyond this: warn (a free-running clock)
  std::int64_t future_ns = 1'000'000'000;       // a stamp this far ahead of its arrival: "future"
};

class ClockCheck {
 public:
  explicit ClockCheck(ClockTolerance tolerance = {});

  // One packet: its sensor time and its arrival (host CLOCK_REALTIME, or a replay's capture
  // time). Called on the receive path: constant time, no allocation, no system call.
  void add(std::int64_t sensor_ns, std::int64_t arrival_ns) noexcept;

  // A replay's --loop started over: the next packet begins a new measurement, neither a step
  // nor time going backwards.
  void restart() noexcept;

  // Off the frame path (about once a second): `reported` (what the sensor says: source, state,
  // grandmaster…; its measured and verdict fields are ignored) with the measured fields filled in
  // and the verdict and problem sentence set, judged also against `host` (the host's own clock,
  // from HostClockWatch; a default ClockStatus when unknown).
  ClockStatus judge(const ClockStatus& reported, const ClockStatus& host,
                    std::int64_t now_realtime_ns);

  const ClockTolerance& tolerance() const noexcept { return tolerance_; }
  std::uint64_t packets() const noexcept { return packets_; }

  // Sizes of the fixed state (no allocation after construction).
  static constexpr std::size_t kSamples = 256;  // recent offsets, one per kSamplePeriodNs at most
  static constexpr std::int64_t kSamplePeriodNs = 4'000'000;  // 250 a second: ~1 s in the ring
  static constexpr std::size_t kSeconds = 64;   // per-second medians for the drift and steps

 private:
  struct Sample {
    std::int64_t arrival_ns;
    std::int64_t offset_ns;
  };
  struct Second {  // the median offset of about one second of packets
    std::int64_t arrival_ns;  // middle of the second
    std::int64_t offset_ns;
  };
  // Something seen now and then (a step, a stamp going backwards, one in the future): how
  // often, the latest, and when (arrival time), so a verdict can say it and forget it later.
  struct Event {
    std::uint64_t count = 0;
    std::int64_t size_ns = 0;      // the step, how far back or how far ahead
    std::int64_t worst_ns = 0;     // the largest |size| since the last restart
    std::int64_t arrival_ns = 0;   // when the last one arrived
    std::int64_t sensor_ns = 0;    // its sensor time
    bool recent = false;           // since the last restart
    void add(std::int64_t size, std::int64_t arrival, std::int64_t sensor) noexcept;
  };

  struct Findings;  // the sentences found while judging, and the worst verdict among them

  void close_second() noexcept;
  ClockStatus measure(const ClockStatus& reported) const;
  // judge()'s two halves: what the offset, its steps and drift say (against `against`, "this
  // host" or "the recording host"), and what the single stamps say (spread, future, backwards).
  void judge_offset(const ClockStatus& measured, const ClockStatus& reported, const ClockStatus& host,
                    const std::string& against, Findings& findings) const;
  void judge_stamps(const ClockStatus& measured, const ClockStatus& reported, const std::string& against,
                    Findings& findings) const;
  bool recent(const Event& event) const noexcept;

  ClockTolerance tolerance_;
  std::uint64_t packets_ = 0;
  // Every packet: the last sensor time, for stamps going backwards.
  bool have_last_ = false;
  std::int64_t last_sensor_ns_ = 0;
  std::int64_t last_arrival_ns_ = 0;
  // Recent offsets, decimated (the median, the spread and the first value within ~1 s).
  std::array<Sample, kSamples> samples_{};
  std::size_t sample_count_ = 0;
  std::size_t sample_next_ = 0;
  std::int64_t last_sample_ns_ = 0;
  // The second being collected, then closed into `seconds_` (its median).
  std::array<std::int64_t, kSamples> second_offsets_{};
  std::size_t second_count_ = 0;
  std::int64_t second_start_ns_ = 0;
  std::int64_t second_last_ns_ = 0;
  std::int64_t pending_step_arrival_ns_ = 0;  // the first packet off the last median, 0: none
  std::int64_t pending_step_sensor_ns_ = 0;
  std::array<Second, kSeconds> seconds_{};  // since the last step or restart
  std::size_t second_total_ = 0;
  bool have_reference_ = false;               // a median of a closed second to compare with
  std::int64_t reference_offset_ns_ = 0;
  // Held over a restart: the last measurement, until the new pass has its own.
  bool have_held_ = false;
  std::int64_t held_offset_ns_ = 0;
  std::int64_t held_spread_ns_ = 0;
  std::int64_t held_sensor_ns_ = 0;
  Event steps_;
  Event backwards_;
  Event future_;
};

}  // namespace sim::timing
