// SPDX-License-Identifier: Apache-2.0
#include "sim/os.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>
#include <string>

namespace sim {

Expected<void> pin_current_thread(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (cpu < 0 || cpu >= CPU_SETSIZE) {
    return Error{ErrorCode::invalid_argument, "CPU " + std::to_string(cpu) + " does not exist"};
  }
  CPU_SET(cpu, &set);
  if (const int err = pthread_setaffinity_np(pthread_self(), sizeof(set), &set); err != 0) {
    return Error{ErrorCode::system_error, "cannot pin to CPU " + std::to_string(cpu) + " (" +
                                              std::strerror(err) +
                                              "); choose a CPU this process may use"};
  }
  return {};
}

Expected<void> set_realtime_priority(int priority) {
  if (priority < sched_get_priority_min(SCHED_FIFO) || priority > sched_get_priority_max(SCHED_FIFO)) {
    return Error{ErrorCode::invalid_argument,
                 "real-time priority " + std::to_string(priority) + " is outside 1–99"};
  }
  sched_param param{};
  param.sched_priority = priority;
  if (const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); err != 0) {
    return Error{ErrorCode::permission_denied,
                 "cannot switch to SCHED_FIFO priority " + std::to_string(priority) + " (" +
                     std::strerror(err) + "); run as root or grant CAP_SYS_NICE"};
  }
  return {};
}

Expected<void> apply_thread_placement(const ThreadPlacement& placement) {
  if (placement.cpu) {
    if (auto pinned = pin_current_thread(*placement.cpu); !pinned) return pinned;
  }
  if (placement.rt_priority) {
    if (auto raised = set_realtime_priority(*placement.rt_priority); !raised) return raised;
  }
  return {};
}

}  // namespace sim
