// SPDX-License-Identifier: Apache-2.0
// The sensor description in the region's header page (internal): how the writer stores it and how
// a reader copies it out and checks it without trusting it. docs/protocol.md, "Sensor description".
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "region.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::detail {

// What is wrong with `info` in two parts: the fault ("frame_id \"9x\" starts with a digit") and
// what to do about it. Both empty when `info` can be stored. sensor_info_problem() joins them;
// a reader finding the fault in a region reports the fault alone (the fix is its writer's).
struct SensorFault {
  std::string fault;
  std::string fix;
  bool empty() const noexcept { return fault.empty(); }
};
SensorFault sensor_info_fault(const SensorInfo& info);

// FrameInfo::sensor_generation for a value of SensorBlock::word: its generation while a
// description is present, else 0.
constexpr std::uint64_t sensor_generation(std::uint64_t word) noexcept {
  return (word & kSensorPresent) != 0 ? word / kSensorGenerationStep : 0;  // as block_generation
}

// A new region's block, carrying on the generation of the region it replaces (`previous_word`,
// 0 for a new stream), so a reader that reopens the name never sees an old generation again.
void start_sensor_block(SensorBlock& block, std::uint64_t previous_word) noexcept;

// Stores `info` (checked by the caller with sensor_info_fault), or removes the description when
// it is empty; either way the generation moves on. For the region's one writer only.
void write_sensor_block(SensorBlock& block, const std::optional<SensorInfo>& info) noexcept;

// Copies the description out of a block the writer may be changing and checks it like a header.
// nullopt: the stream has none. An Error: the block is damaged (the sentence names the fault).
// `generation` (optional) receives the generation of the copy returned.
Expected<std::optional<SensorInfo>> read_sensor_block(const SensorBlock& block,
                                                      std::uint64_t* generation = nullptr);

// The record of `info`, every byte defined (zero outside the fields in use).
SensorRecord to_record(const SensorInfo& info) noexcept;

}  // namespace sim::detail
