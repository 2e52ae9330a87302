// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/time_client.hpp"

#include "sim/clock.hpp"
#include "sim/timing/clock_notes.hpp"

namespace sim::ouster {
namespace {

constexpr std::size_t max_time_answer = 256u << 10;  // a time answer is a few KB

}  // namespace

Expected<ClockStatus> fetch_clock(const HttpEndpoint& sensor, std::string& path) {
  auto answer = http_get(sensor, path, max_time_answer, "time");
  std::string asked = path;
  if (answer && answer->status == 404 && path == time_path) {
    auto older = http_get(sensor, old_time_path, max_time_answer, "time");
    if (older && older->status == 200) path = old_time_path;
    asked = std::string(time_path) + " and " + old_time_path;
    answer = std::move(older);
  }
  if (!answer) return answer.error();
  const std::string who = "sensor " + sensor.host + ":" + std::to_string(sensor.port);
  if (answer->status != 200) {
    return Error{ErrorCode::system_error, who + " answered '" + answer->status_line + "' to GET " + asked +
                                              "; it does not report its clock there"};
  }
  auto clock = clock_status_from_time_json(answer->body);
  if (!clock) return Error{clock.error().code, who + ": " + clock.error().message};
  return clock;
}

ClockStatus HttpClockReader::operator()() {
  auto clock = fetch_clock(sensor_, path_);
  if (!clock) return timing::clock_read_failed(clock.error().message);
  clock->reported_ns = realtime_ns();
  return std::move(clock.value());
}

}  // namespace sim::ouster
