// SPDX-License-Identifier: Apache-2.0
// The sensor's clock over its HTTP API, asked about once a second off the frame path:
//
//   sim::apps::ClockPoll poll(sim::ouster::HttpClockReader(sensor), 1s);
//   poll.latest() -> sim::ClockStatus: source (ptp/sync_pulse/pps_nmea/free_running), state,
//                    offset from master, path delay, grandmaster, UTC offset, timescale
//
// GET /api/v1/time; when that is 404 (firmware 2.0 and older) GET /api/v1/system/time, and that
// path from then on. Each GET ends by sensor.timeout; a sensor that does not answer costs one
// sentence (ClockStatus::problem), never a wait for the stream.
#pragma once

#include <string>

#include "sim/clock_status.hpp"
#include "sim/ouster/metadata_client.hpp"
#include "sim/ouster/time_status.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

inline constexpr char time_path[] = "/api/v1/time";
inline constexpr char old_time_path[] = "/api/v1/system/time";  // firmware ≤ 2.0

// The sensor's clock from `path`; on a 404 from time_path, from old_time_path, and `path` is set
// to it. Errors, one sentence naming the sensor and the path.
Expected<ClockStatus> fetch_clock(const HttpEndpoint& sensor, std::string& path);

// A std::function<ClockStatus()> for a poller: each call one GET, reported_ns set to when it was
// read; a failed one has source and state unknown, reported_ns 0 and the sentence in `problem`.
class HttpClockReader {
 public:
  explicit HttpClockReader(HttpEndpoint sensor) : sensor_(std::move(sensor)) {}
  ClockStatus operator()();

 private:
  HttpEndpoint sensor_;
  std::string path_ = time_path;
};

}  // namespace sim::ouster
