// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/clock_poll.hpp"

#include <utility>

#include "sim/clock.hpp"

namespace sim::apps {

ClockPoll::ClockPoll(std::function<ClockStatus()> read, std::chrono::milliseconds period)
    : notes_(std::make_shared<Notes>()),
      poller_(
          [read = std::move(read), shared = notes_] {
            ClockStatus status = read();  // bounded by the reader's own deadline
            auto notes = shared->notes.update(status, monotonic_ns());
            std::lock_guard lock(shared->mutex);
            for (auto& note : notes) shared->pending.push_back(std::move(note));
            return status;
          },
          period) {}

std::vector<std::string> ClockPoll::take_notes() {
  std::lock_guard lock(notes_->mutex);
  return std::exchange(notes_->pending, {});
}

}  // namespace sim::apps
