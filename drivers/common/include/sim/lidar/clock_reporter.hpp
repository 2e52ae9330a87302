// SPDX-License-Identifier: Apache-2.0
// ClockReporter: the clock check every LiDAR stream shares (Hesai, Velodyne, Ouster), live and
// replayed. Each packet's own sensor time goes in with its arrival (live: the kernel's receive
// stamp of the datagram; a replay: the capture's time of the record, the recording host's
// clock); about once a second the check is judged and written to the stream (Writer::set_clock).
//
//   stream.clock().add(*result.packet_ns, datagram.arrival_ns);     // per packet: cheap
//   stream.clock().tick(stream.writer(), datagram.arrival_ns);      // writes once a second
//
// What the sensor says of its own synchronisation (Hesai PTC, Ouster HTTP, Velodyne position
// packets) and the host's come from optional sources, asked only when judging: they must return
// what they last read (a thread or a poll of their own reads the sensor), never wait.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "sim/clock_status.hpp"
#include "sim/timing/clock_check.hpp"
#include "sim/writer.hpp"

namespace sim::lidar {

// What a stream's stamps are and where its clock is judged against.
enum class ClockBase {
  sensor,     // live: the sensor's clock against each datagram's arrival on this host
  replayed,   // a replay with recorded stamps: against the capture's time of each record
  restamped,  // a replay moved to the present: host time (the stamps against the replay's now)
};

struct ClockSources {
  std::function<ClockStatus()> reported;  // the sensor's own report; empty: none
  std::function<ClockStatus()> host;      // the host's synchronisation; empty: unknown
};

class ClockReporter {
 public:
  static constexpr std::int64_t kPeriodNs = 1'000'000'000;   // judged about once a second
  static constexpr std::int64_t kFirstNs = 250'000'000;      // the first judgement: after 0.25 s

  explicit ClockReporter(timing::ClockTolerance tolerance = {}) noexcept : check_(tolerance) {}

  // One packet's sensor time and arrival (see ClockBase): constant time, no allocation.
  void add(std::int64_t sensor_ns, std::int64_t arrival_ns) noexcept { check_.add(sensor_ns, arrival_ns); }
  // The same for a decoder's result: nothing when the packet carried no sensor time.
  void add(const std::optional<std::int64_t>& sensor_ns, std::int64_t arrival_ns) noexcept {
    if (sensor_ns) check_.add(*sensor_ns, arrival_ns);
  }
  // A live packet as the stream stamps it: its sensor time plus the stream's stamp offset (a
  // --tai-correction), so a corrected clock is judged by what readers get.
  void add(const std::optional<std::int64_t>& sensor_ns, std::int64_t stamp_offset_ns,
           std::int64_t arrival_ns) noexcept;
  // A replay's --loop started over: neither a step nor time going backwards.
  void restart() noexcept { check_.restart(); }

  void set_base(ClockBase base) noexcept { base_ = base; }
  ClockBase base() const noexcept { return base_; }
  void set_sources(ClockSources sources) { sources_ = std::move(sources); }
  void set_tolerance(const timing::ClockTolerance& tolerance) noexcept;

  // When a second has passed since the last judgement (`now_realtime_ns`, the host's
  // CLOCK_REALTIME or a datagram's arrival stamp), judges the clock and writes it to the stream.
  // The first judgement comes a quarter second after the first packet, so a reader has it within
  // a second. Returns the judgement when it wrote one.
  // With `at_once` it judges and writes now, whatever the time (the end of a replay).
  std::optional<ClockStatus> tick(Writer& writer, std::int64_t now_realtime_ns, bool at_once = false);
  // Judges now without writing (a test, a status line).
  ClockStatus judge(std::int64_t now_realtime_ns);
  const std::optional<ClockStatus>& last() const noexcept { return last_; }
  const timing::ClockCheck& check() const noexcept { return check_; }

 private:
  timing::ClockCheck check_;
  ClockBase base_ = ClockBase::sensor;
  ClockSources sources_;
  std::int64_t first_tick_ns_ = 0;  // the first tick that saw packets
  std::int64_t last_judged_ns_ = 0;
  std::optional<ClockStatus> last_;
};

// Writes `clock` to the stream (Writer::set_clock); false when the writer refused it.
bool write_clock(Writer& writer, const ClockStatus& clock);

}  // namespace sim::lidar
