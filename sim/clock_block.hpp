// SPDX-License-Identifier: Apache-2.0
// The clock record in the region's header page (internal): how the writer stores it and how a
// reader copies it out and checks it without trusting it. docs/protocol.md, "Clock record".
#pragma once

#include <cstdint>
#include <optional>

#include "region.hpp"
#include "sim/clock_status.hpp"
#include "sim/result.hpp"

namespace sim::detail {

// FrameInfo::clock_generation for a value of ClockBlock::word.
std::uint64_t clock_generation(std::uint64_t word) noexcept;

// A new region's block, carrying on the generation of the region it replaces (0: a new stream).
void start_clock_block(ClockBlock& block, std::uint64_t previous_word) noexcept;

// Stores `clock` (checked by the caller with clock_status_problem), or removes the record when
// it is empty; either way the generation moves on. For the region's one writer only.
void write_clock_block(ClockBlock& block, const std::optional<ClockStatus>& clock) noexcept;

// Copies the record out of a block the writer may be changing and checks it like a header.
// nullopt: the stream has none. An Error: the block is damaged (the sentence names the fault).
Expected<std::optional<ClockStatus>> read_clock_block(const ClockBlock& block,
                                                      std::uint64_t* generation = nullptr);

// The record of `clock`, every byte defined (zero outside the fields in use).
ClockRecord to_record(const ClockStatus& clock) noexcept;

}  // namespace sim::detail
