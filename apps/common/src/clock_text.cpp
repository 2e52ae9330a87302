// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/clock_text.hpp"

#include <cstdio>

#include "sim/apps/sensor_text.hpp"

namespace sim::apps {
namespace {

template <typename T>
std::string optional_number(const std::optional<T>& value) {
  return value ? std::to_string(*value) : "null";
}

std::string quoted(const char* text) { return json_string(text); }

}  // namespace

ClockStatus effective_clock(const StreamClock& stream) {
  if (stream.clock) return *stream.clock;
  ClockStatus none;
  none.problem = stream.problem.empty()
                     ? "the stream's writer does not report its clock (a program older than the clock record, "
                       "or one that has not measured it yet)"
                     : stream.problem;
  return none;
}

std::string describe_clock(const StreamClock& stream) { return summary(effective_clock(stream)); }

std::string clock_json(const StreamClock& stream) {
  const ClockStatus c = effective_clock(stream);
  char drift[32];
  std::snprintf(drift, sizeof drift, "%.3f", c.drift_ppm);
  std::string out = "{";
  json_field(out, "source", quoted(to_string(c.source)));
  json_field(out, "state", quoted(to_string(c.state)));
  json_field(out, "offset_to_host_ns", optional_number(c.offset_to_host_ns));
  json_field(out, "verdict", quoted(to_string(c.verdict)));
  json_field(out, "problem", json_string(c.problem));
  json_field(out, "spread_ns", std::to_string(c.spread_ns));
  json_field(out, "drift_ppm", drift);
  json_field(out, "steps", std::to_string(c.steps));
  json_field(out, "last_step_ns", std::to_string(c.last_step_ns));
  json_field(out, "packets_measured", std::to_string(c.packets_measured));
  json_field(out, "measured_ns", std::to_string(c.measured_ns));
  json_field(out, "ptp_domain", c.ptp_domain >= 0 ? std::to_string(c.ptp_domain) : "null");
  json_field(out, "offset_from_master_ns", optional_number(c.offset_from_master_ns));
  json_field(out, "path_delay_ns", optional_number(c.path_delay_ns));
  json_field(out, "grandmaster", c.grandmaster.empty() ? "null" : json_string(c.grandmaster));
  json_field(out, "utc_offset_s", optional_number(c.utc_offset_s));
  json_field(out, "ptp_timescale", c.ptp_timescale ? "true" : "false");
  json_field(out, "tai_correction_ns", std::to_string(c.tai_correction_ns));
  json_field(out, "reported_ns", std::to_string(c.reported_ns));
  json_field(out, "stamps", quoted(to_string(c.stamps)));
  json_field(out, "summary", json_string(summary(c)));
  return out + "}";
}

std::string host_clock_json(const ClockStatus& host) {
  std::string out = "{";
  json_field(out, "source", quoted(to_string(host.source)));
  json_field(out, "state", quoted(to_string(host.state)));
  json_field(out, "offset_ns", optional_number(host.offset_from_master_ns));
  json_field(out, "grandmaster", host.grandmaster.empty() ? "null" : json_string(host.grandmaster));
  json_field(out, "ptp_domain", host.ptp_domain >= 0 ? std::to_string(host.ptp_domain) : "null");
  json_field(out, "path_delay_ns", optional_number(host.path_delay_ns));
  json_field(out, "utc_offset_s", optional_number(host.utc_offset_s));
  json_field(out, "problem", json_string(host.problem));
  json_field(out, "summary", json_string(summary(host)));
  return out + "}";
}

}  // namespace sim::apps
