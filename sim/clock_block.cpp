// SPDX-License-Identifier: Apache-2.0
#include "clock_block.hpp"

#include <cstring>
#include <string>

#include "fixed_text.hpp"
#include "seqlock_block.hpp"

namespace sim::detail {

namespace {

template <typename T>
void put_optional(std::uint32_t& flags, std::uint32_t bit, T& field, const std::optional<T>& value) {
  if (!value) return;
  flags |= bit;
  field = *value;
}

template <typename T>
std::optional<T> take_optional(std::uint32_t flags, std::uint32_t bit, T value) {
  if ((flags & bit) == 0) return std::nullopt;
  return value;
}

// The record as a ClockStatus, or a fault phrase for what is not a valid field.
Expected<ClockStatus> decode(const ClockRecord& r) {
  const auto fault = [](std::string text) { return Error{ErrorCode::region_invalid, std::move(text)}; };
  if ((r.flags & ~kClockKnownFlags) != 0) return fault("it uses flags this library does not know");
  ClockStatus c;
  if (!take_text(r.grandmaster, c.grandmaster)) return fault("its grandmaster is not a NUL-terminated string");
  if (!take_text(r.problem, c.problem)) return fault("its problem is not a NUL-terminated string");
  c.source = static_cast<ClockSource>(r.source);
  c.state = static_cast<ClockState>(r.state);
  c.ptp_domain = r.ptp_domain;
  c.offset_from_master_ns = take_optional(r.flags, kClockHasOffsetFromMaster, r.offset_from_master_ns);
  c.path_delay_ns = take_optional(r.flags, kClockHasPathDelay, r.path_delay_ns);
  c.utc_offset_s = take_optional(r.flags, kClockHasUtcOffset, r.utc_offset_s);
  c.ptp_timescale = (r.flags & kClockPtpTimescale) != 0;
  c.tai_correction_ns = r.tai_correction_ns;
  c.reported_ns = r.reported_ns;
  c.offset_to_host_ns = take_optional(r.flags, kClockHasOffsetToHost, r.offset_to_host_ns);
  c.spread_ns = r.spread_ns;
  c.drift_ppm = r.drift_ppm;
  c.steps = r.steps;
  c.last_step_ns = r.last_step_ns;
  c.packets_measured = r.packets_measured;
  c.measured_ns = r.measured_ns;
  c.verdict = static_cast<ClockVerdict>(r.verdict);
  c.stamps = static_cast<StampClock>(r.stamps);
  // Enums in range, texts clean, numbers finite: what a writer could have stored.
  if (const std::string problem = clock_status_problem(c); !problem.empty()) return fault(problem);
  // Every byte outside the fields in use must be zero, as the writer leaves it.
  const ClockRecord canonical = to_record(c);
  if (std::memcmp(&canonical, &r, sizeof r) != 0) return fault("it holds bytes outside its fields");
  return c;
}

}  // namespace

ClockRecord to_record(const ClockStatus& c) noexcept {
  ClockRecord r;
  std::memset(&r, 0, sizeof r);  // every byte: readers compare records bytewise
  r.source = static_cast<std::uint32_t>(c.source);
  r.state = static_cast<std::uint32_t>(c.state);
  r.ptp_domain = c.ptp_domain;
  put_optional(r.flags, kClockHasOffsetFromMaster, r.offset_from_master_ns, c.offset_from_master_ns);
  put_optional(r.flags, kClockHasPathDelay, r.path_delay_ns, c.path_delay_ns);
  put_optional(r.flags, kClockHasUtcOffset, r.utc_offset_s, c.utc_offset_s);
  if (c.ptp_timescale) r.flags |= kClockPtpTimescale;
  r.verdict = static_cast<std::uint32_t>(c.verdict);
  r.tai_correction_ns = c.tai_correction_ns;
  r.reported_ns = c.reported_ns;
  put_optional(r.flags, kClockHasOffsetToHost, r.offset_to_host_ns, c.offset_to_host_ns);
  r.spread_ns = c.spread_ns;
  r.drift_ppm = c.drift_ppm;
  r.steps = c.steps;
  r.stamps = static_cast<std::uint32_t>(c.stamps);
  r.last_step_ns = c.last_step_ns;
  r.packets_measured = c.packets_measured;
  r.measured_ns = c.measured_ns;
  put_text(r.grandmaster, c.grandmaster);
  put_text(r.problem, c.problem);
  return r;
}

std::uint64_t clock_generation(std::uint64_t word) noexcept { return block_generation(word); }

void start_clock_block(ClockBlock& block, std::uint64_t previous_word) noexcept {
  start_block(block.word, previous_word);
}

void write_clock_block(ClockBlock& block, const std::optional<ClockStatus>& clock) noexcept {
  const ClockRecord record = clock ? to_record(*clock) : ClockRecord{};
  write_block(block.word, block.record, record, clock.has_value());
}

Expected<std::optional<ClockStatus>> read_clock_block(const ClockBlock& block,
                                                      std::uint64_t* generation) {
  return read_block<ClockStatus>(block.word, block.record, "clock record", generation, decode);
}

}  // namespace sim::detail
