// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/ptc_clock.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include "sim/clock.hpp"
#include "sim/timing/clock_notes.hpp"

namespace sim::hesai {
namespace {

// One exchange with what is left of the round's deadline (CLOCK_MONOTONIC); the first has the
// whole timeout (and its messages say so).
Expected<std::vector<std::uint8_t>> ask(const PtcEndpoint& sensor, std::int64_t deadline_ns, std::uint8_t command,
                                        std::span<const std::uint8_t> payload, const char* what) {
  PtcEndpoint bounded = sensor;
  if (command != ptc::get_ptp_config) {
    const std::int64_t left_ms = (deadline_ns - monotonic_ns()) / 1'000'000;
    bounded.timeout = std::chrono::milliseconds(std::max<std::int64_t>(left_ms, 1));
  }
  return ptc_exchange(bounded, command, payload, what);
}

// Keeps the parsed answer when the sensor answered; a refused or malformed answer leaves the
// part out. A connection failure is the round's end: `failure` says why.
template <class Part, class Parse>
bool take(Expected<std::vector<std::uint8_t>> answer, std::optional<Part>& part, Parse parse,
          std::optional<Error>& failure) {
  if (!answer) {
    if (answer.error().code == ErrorCode::system_error) {
      failure = answer.error();
      return false;
    }
    return true;
  }
  auto parsed = parse(std::span<const std::uint8_t>(*answer));
  if (parsed) part = std::move(parsed.value());
  return true;
}

}  // namespace

Expected<ptc::ClockReplies> fetch_clock_replies(const PtcEndpoint& sensor, std::optional<Model> model) {
  const std::int64_t deadline = monotonic_ns() + static_cast<std::int64_t>(sensor.timeout.count()) * 1'000'000;
  ptc::ClockReplies replies;
  std::optional<Error> failure;
  const auto layout = model ? ptc::status_layout(*model) : std::nullopt;
  bool go = take(ask(sensor, deadline, ptc::get_ptp_config, {}, "PTP configuration"), replies.config,
                 ptc::parse_ptp_config, failure);
  go = go && take(ask(sensor, deadline, ptc::get_lidar_status, {}, "LiDAR status"), replies.status,
                  [&](std::span<const std::uint8_t> p) { return ptc::parse_lidar_status(p, layout); }, failure);
  const auto query = [&](ptc::PtpQuery q, const char* what) {
    const std::array<std::uint8_t, 1> payload{static_cast<std::uint8_t>(q)};
    return ask(sensor, deadline, ptc::ptp_diagnostics, payload, what);
  };
  go = go && take(query(ptc::PtpQuery::status, "PTP status"), replies.ptp, ptc::parse_ptp_status, failure);
  go = go && take(query(ptc::PtpQuery::port_data_set, "PTP port data set"), replies.port,
                  ptc::parse_port_data_set, failure);
  go = go && take(query(ptc::PtpQuery::time_status_np, "PTP time status"), replies.time_status,
                  ptc::parse_time_status_np, failure);
  go = go && take(query(ptc::PtpQuery::grandmaster_settings_np, "PTP grandmaster settings"),
                  replies.grandmaster, ptc::parse_grandmaster_settings_np, failure);
  const bool none = !replies.config && !replies.status && !replies.ptp && !replies.port &&
                    !replies.time_status && !replies.grandmaster;
  if (failure && none) return *failure;
  if (none) {
    return Error{ErrorCode::invalid_argument, "sensor " + sensor.host + ":" + std::to_string(sensor.port) +
                                                  " answered none of the PTC clock questions (0x26, 0x09, "
                                                  "0x06); its firmware may not report its clock"};
  }
  return replies;
}

ClockStatus PtcClockReader::operator()() const {
  auto replies = fetch_clock_replies(sensor_, model_);
  if (!replies) return timing::clock_read_failed(replies.error().message);
  ClockStatus clock = ptc::clock_status(*replies);
  clock.reported_ns = realtime_ns();
  return clock;
}

}  // namespace sim::hesai
