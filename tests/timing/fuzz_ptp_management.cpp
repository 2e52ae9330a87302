// SPDX-License-Identifier: Apache-2.0
// Fuzzes the parser of ptp4l's management responses (outside bytes from a Unix socket) and the
// mapping of what it says to the clock record. Input: one datagram; or "SIMM" then records of
// [u16 big-endian length][datagram], folded together as one conversation with ptp4l. The record
// must always be storable (sim::clock_status_problem finds nothing).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "sim/timing/host_clock.hpp"
#include "sim/timing/ptp_management.hpp"

namespace {

void add(const std::uint8_t* data, std::size_t size, sim::timing::Ptp4lAnswer& answer) {
  auto response = sim::timing::ptp::parse_response(sim::span<const std::uint8_t>(data, size));
  if (!response) {
    if (response.error().message.empty()) std::abort();  // always one sentence
    if (answer.problem.empty()) answer.problem = response.error().message;
    return;
  }
  sim::timing::fold_response(*response, answer);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sim::timing::Ptp4lAnswer answer;
  answer.socket = "/fuzz";
  if (size >= 4 && std::memcmp(data, "SIMM", 4) == 0) {
    std::size_t at = 4;
    while (at + 2 <= size) {
      const std::size_t length = std::size_t{data[at]} << 8 | data[at + 1];
      at += 2;
      if (length > size - at) break;
      add(data + at, length, answer);
      at += length;
    }
  } else {
    add(data, size, answer);
  }
  const auto host = sim::timing::host_clock_from(answer, {}, sim::timing::KernelClock{}, 1);
  if (host.status.problem.size() > sim::ClockStatus::kMaxProblem ||
      host.status.grandmaster.size() > sim::ClockStatus::kMaxGrandmaster ||
      host.description.empty() || !sim::clock_status_problem(host.status).empty()) {
    std::abort();
  }
  return 0;
}
