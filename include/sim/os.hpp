// SPDX-License-Identifier: Apache-2.0
// Placement of the calling thread: the knobs behind every tool's --cpu and --rt-priority.
#pragma once

#include <optional>

#include "sim/result.hpp"

namespace sim {

// Pins the calling thread to one CPU.
Expected<void> pin_current_thread(int cpu);
// Runs the calling thread under SCHED_FIFO at `priority` (1–99); needs CAP_SYS_NICE or root.
Expected<void> set_realtime_priority(int priority);

// Where a tool's working thread runs: its --cpu and --rt-priority (or a config file's cpu and
// rt_priority). Unset means "leave as the system chose".
struct ThreadPlacement {
  std::optional<int> cpu;
  std::optional<int> rt_priority;
};
// Pins, then raises the priority, of the calling thread; the first error, if any.
Expected<void> apply_thread_placement(const ThreadPlacement& placement);

}  // namespace sim
