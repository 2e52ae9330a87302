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
#include <string>

#include "sim/clock_status.hpp"
#include "sim/timing/stamp_switch.hpp"
#include "sim/timing/clock_check.hpp"
#include "sim/writer.hpp"

namespace sim::timing {

// What a stream's stamps are and where its clock is judged against.
enum class ClockBase {
  sensor,     // live: the sensor's clock against each datagram's arrival on this host
  replayed,   // a replay with recorded stamps: against the capture's time of each record
  restamped,  // a replay moved to the present: host time (the stamps against the replay's now)
};

struct ClockSources {
  std::function<ClockStatus()> reported;  // the sensor's own report; empty: none
  std::function<ClockStatus()> host;      // the host's synchronisation; empty: unknown
  // What the live program asks of the stream's stamps (--stamp-fallback; a replay has none), and
  // where each switch of their clock is told, one line (empty: stderr).
  StampFallback stamp_fallback = StampFallback::off;
  std::function<void(const std::string& line)> log{};
};

class ClockReporter {
 public:
  static constexpr std::int64_t kPeriodNs = 1'000'000'000;   // judged about once a second
  static constexpr std::int64_t kFirstNs = 250'000'000;      // the first judgement: after 0.25 s

  explicit ClockReporter(ClockTolerance tolerance = {}) noexcept : check_(tolerance) {}

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
  // The sources and the stamp fallback (a switch already under way is kept when it is the same).
  void set_sources(ClockSources sources);
  void set_tolerance(const ClockTolerance& tolerance) noexcept;

  // When a second has passed since the last judgement (`now_realtime_ns`, the host's
  // CLOCK_REALTIME or a datagram's arrival stamp), judges the clock and writes it to the stream.
  // The first judgement comes a quarter second after the first packet, so a reader has it within
  // a second. Returns the judgement when it wrote one.
  // With `at_once` it judges and writes now, whatever the time (the end of a replay).
  std::optional<ClockStatus> tick(Writer& writer, std::int64_t now_realtime_ns, bool at_once = false);
  // Judges now without writing (a test, a status line).
  ClockStatus judge(std::int64_t now_realtime_ns);
  // The record before the first judgement: which clock the stamps are in is known from the start
  // (the base, the sensor's report, --stamp-fallback); the verdict is unknown until judged.
  ClockStatus unjudged() const;
  static constexpr const char* kNotJudged = "not judged yet: waiting for the first second of packets";
  // Writes the stream's first record, when none was written to it: the unjudged one (or the last
  // judgement, for a stream created anew). frame_stamp and tick call it, so the first frame
  // carries its FrameInfo::stamp_clock; a driver that commits frames itself calls it first.
  void start(Writer& writer) {
    if (!record_written_) write_first(writer);
  }
  // The stream was created anew (a camera back with another format): start writes again.
  void new_stream() noexcept { record_written_ = false; }
  const std::optional<ClockStatus>& last() const noexcept { return last_; }

  // The stamp a frame is published with: `sensor_stamp_ns` (the sensor's, the stamp offset
  // applied), or with --stamp-fallback host its arrival `host_ns` while the last judgement is
  // error (see StampSwitch). A switch rewrites the stream's clock record before the frame is
  // committed, so the frame's FrameInfo::stamp_clock names the clock of its stamp.
  std::int64_t frame_stamp(Writer& writer, std::int64_t sensor_stamp_ns, std::int64_t host_ns) {
    start(writer);
    if (!stamps_.enabled()) return sensor_stamp_ns;
    return switch_stamp(writer, sensor_stamp_ns, host_ns);
  }
  const StampSwitch& stamps() const noexcept { return stamps_; }
  const ClockCheck& check() const noexcept { return check_; }

 private:
  ClockCheck check_;
  ClockBase base_ = ClockBase::sensor;
  ClockSources sources_;
  std::int64_t first_tick_ns_ = 0;  // the first tick that saw packets
  std::int64_t last_judged_ns_ = 0;
  std::optional<ClockStatus> last_;     // as written: with the stamps it describes
  std::optional<ClockStatus> judged_;   // the sensor's clock as judged, before that
  StampSwitch stamps_;
  bool record_written_ = false;

  std::int64_t switch_stamp(Writer& writer, std::int64_t sensor_stamp_ns, std::int64_t host_ns);
  void write_first(Writer& writer);
  // What the sources report, as the base makes it: the half of a record a judgement starts from.
  ClockStatus reported() const;
};

// Writes `clock` to the stream (Writer::set_clock); false when the writer refused it.
bool write_clock(Writer& writer, const ClockStatus& clock);

}  // namespace sim::timing
