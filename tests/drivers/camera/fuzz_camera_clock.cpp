// SPDX-License-Identifier: Apache-2.0
// Fuzzes what a GenICam camera says of its PTP clock (genicam_clock_status): the status and
// servo texts come from the camera. Input: [flags][offset i64 LE][grandmaster u64 LE] then the
// status text, a NUL, the servo text. The record must always be storable.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "sim/camera/camera_clock.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 17) return 0;
  sim::camera::PtpReading ptp;
  const std::uint8_t flags = data[0];
  ptp.has_ptp = (flags & 1) != 0;
  ptp.enabled = (flags & 2) != 0;
  std::int64_t offset = 0;
  std::uint64_t grandmaster = 0;
  std::memcpy(&offset, data + 1, 8);
  std::memcpy(&grandmaster, data + 9, 8);
  if (flags & 4) ptp.offset_from_master_ns = offset;
  if (flags & 8) ptp.grandmaster = grandmaster;
  const std::string text(reinterpret_cast<const char*>(data + 17), size - 17);
  const std::size_t nul = text.find('\0');
  ptp.status = text.substr(0, nul);
  if (nul != std::string::npos) ptp.servo = text.substr(nul + 1);
  const sim::ClockStatus clock = sim::camera::genicam_clock_status(ptp, (flags & 16) != 0, 1);
  if (clock.problem.size() > sim::ClockStatus::kMaxProblem) __builtin_trap();
  if (clock.grandmaster.size() > sim::ClockStatus::kMaxGrandmaster) __builtin_trap();
  return 0;
}
