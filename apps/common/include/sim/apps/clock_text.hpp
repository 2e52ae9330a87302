// SPDX-License-Identifier: Apache-2.0
// A stream's clock (sim/clock_status.hpp) for people and scripts, the same in every tool
// (sim_ls, sim_echo, sim_foxglove):
//   ptp locked, domain 0, grandmaster 00a069.fffe.0b552d, offset to host +12 µs ±3 µs: ok
// and as one JSON object whose names scripts rely on: source, state, offset_to_host_ns (an
// integer, sensor − host, null until measured), verdict (ok, warn, error, unknown) and problem
// (the sentence, "" when ok), with the rest of the record beside them.
#pragma once

#include <optional>
#include <string>

#include "sim/clock_status.hpp"

namespace sim::apps {

// What Reader::clock() or StreamStatus gave: the record, or none (`problem` says why: damaged,
// or empty when the writer reports no clock).
struct StreamClock {
  std::optional<ClockStatus> clock;
  std::string problem;
};

// The record as tools judge it: a stream without one has verdict unknown and a problem saying
// that its writer does not report its clock; a damaged one says so.
ClockStatus effective_clock(const StreamClock& stream);

// One line (no newline) for a person: sim::summary of effective_clock.
std::string describe_clock(const StreamClock& stream);

// One JSON object with every field of effective_clock and its summary.
std::string clock_json(const StreamClock& stream);

// The host's clock as one JSON object: source, state, offset_ns (offset from its master, null
// when it has none), grandmaster, ptp_domain, path_delay_ns, utc_offset_s, summary.
std::string host_clock_json(const ClockStatus& host);

}  // namespace sim::apps
