// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: arbitrary bytes as a sensor's PTC clock answers (0x26, 0x09 in either layout,
// 0x06 queries 1–4) through their readers and into a ClockStatus.
// Input: [layout selector] then six records [u8 length][payload], one per answer (a missing
// record: that answer not given). Invariants: no out-of-bounds access (ASan), every refusal is
// one line, the grandmaster is empty or "xxxxxx.xxxx.xxxxxx", the domain -1 or a byte.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "sim/hesai/ptc_time.hpp"

using namespace sim::hesai;

namespace {

template <class T>
void keep(sim::Expected<T> parsed, std::optional<T>& part) {
  if (!parsed) {
    if (parsed.error().message.empty() || parsed.error().message.find('\n') != std::string::npos) __builtin_trap();
    return;
  }
  part = std::move(parsed.value());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t selector = data[0];
  std::span<const std::uint8_t> rest(data + 1, size - 1);
  std::span<const std::uint8_t> records[6];
  bool present[6] = {};
  for (int i = 0; i < 6 && !rest.empty(); ++i) {
    const std::size_t length = std::min<std::size_t>(rest[0], rest.size() - 1);
    records[i] = rest.subspan(1, length);
    present[i] = true;
    rest = rest.subspan(1 + length);
  }
  std::optional<ptc::StatusLayout> layout;
  if (selector % 3 == 1) layout = ptc::StatusLayout::xt;
  if (selector % 3 == 2) layout = ptc::StatusLayout::qt;
  ptc::ClockReplies r;
  if (present[0]) keep(ptc::parse_ptp_config(records[0]), r.config);
  if (present[1]) keep(ptc::parse_lidar_status(records[1], layout), r.status);
  if (present[2]) keep(ptc::parse_ptp_status(records[2]), r.ptp);
  if (present[3]) keep(ptc::parse_port_data_set(records[3]), r.port);
  if (present[4]) keep(ptc::parse_time_status_np(records[4]), r.time_status);
  if (present[5]) keep(ptc::parse_grandmaster_settings_np(records[5]), r.grandmaster);
  const sim::ClockStatus clock = ptc::clock_status(r);
  if (!clock.grandmaster.empty() && (clock.grandmaster.size() != 18 || clock.grandmaster[6] != '.')) __builtin_trap();
  if (clock.ptp_domain < -1 || clock.ptp_domain > 255) __builtin_trap();
  if (clock.utc_offset_s && (*clock.utc_offset_s < -32768 || *clock.utc_offset_s > 32767)) __builtin_trap();
  return 0;
}
