// SPDX-License-Identifier: Apache-2.0
// The sensor's clock over PTC, asked about once a second off the frame path:
//
//   sim::apps::ClockPoll poll(sim::hesai::PtcClockReader(sensor, model), 1s);
//   poll.latest() -> sim::ClockStatus: source (ptp/gptp/pps_nmea/free_running), state, domain,
//                    offset from master, path delay, grandmaster, UTC offset, when it was read
//
// One read asks 0x26 (PTP config), 0x09 (LiDAR status) and 0x06 queries 1–4 (PTP status, port
// data set, time status, grandmaster settings), one connection each, all within sensor.timeout
// together. A command the firmware lacks is left out; a sensor that does not answer at all ends
// the read at once with one sentence (ClockStatus::problem), never a wait for the stream.
#pragma once

#include <optional>

#include "sim/clock_status.hpp"
#include "sim/hesai/model.hpp"
#include "sim/hesai/ptc_client.hpp"
#include "sim/hesai/ptc_time.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

// One round of questions; an error (one sentence) only when the sensor answered none of them.
// model: where 0x09 keeps its fields (nullopt: told by the answer's size).
Expected<ptc::ClockReplies> fetch_clock_replies(const PtcEndpoint& sensor, std::optional<Model> model);

// A std::function<ClockStatus()> for a poller: each call one round, reported_ns set to when it
// was read; a failed round has source and state unknown, reported_ns 0 and the sentence in
// `problem`.
class PtcClockReader {
 public:
  PtcClockReader(PtcEndpoint sensor, std::optional<Model> model) : sensor_(std::move(sensor)), model_(model) {}
  ClockStatus operator()() const;

 private:
  PtcEndpoint sensor_;
  std::optional<Model> model_;
};

}  // namespace sim::hesai
