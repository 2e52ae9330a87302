// SPDX-License-Identifier: Apache-2.0
// The decisions of an adaptive wait (internal): when to sleep, when to spin, when to just block.
// Pure logic on numbers the caller passes in, so it is tested against a simulated clock.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace sim::detail {

// What the writer's header says about the stream's timing (Liveness), read by the caller.
struct StreamTiming {
  std::int64_t latest_publish_ns = 0;  // CLOCK_MONOTONIC of the newest frame; 0 before any
  std::int64_t period_ns = 0;          // smoothed publish period of the current writer; 0: unknown
  std::int64_t jitter_ns = 0;          // its typical deviation
  std::uint64_t frames_this_writer = 0;
};

// How late this reader's timed futex sleeps typically wake (a loaded machine or a VM wakes later
// than the timer asked: on this project's VM 120–170 µs, now and then milliseconds): the planner
// starts the spin that much earlier. It tracks the median, one small step toward each sample, so
// a rare wake-up milliseconds late (the vCPU was descheduled) cannot drag the window so early
// that it ends before the frame comes, as a mean would.
class WakeLateness {
 public:
  void add(std::int64_t late_ns) noexcept {
    if (late_ns < 0) late_ns = 0;
    if (!seeded_) {
      median_ns_ = late_ns;
      seeded_ = true;
      return;
    }
    const std::int64_t step = std::max<std::int64_t>(kMinStepNs, median_ns_ / 16);
    if (late_ns > median_ns_) median_ns_ += step;
    if (late_ns < median_ns_) median_ns_ -= std::min(step, median_ns_);
  }
  // A wake-up known only to be at least this late (a publish woke the reader after its timer
  // should have): counts as a sample above the median when it is above it.
  void add_at_least(std::int64_t late_ns) noexcept {
    if (seeded_ && late_ns > median_ns_) add(late_ns);
  }
  std::int64_t ns() const noexcept { return median_ns_; }

 private:
  static constexpr std::int64_t kMinStepNs = 1'000;
  std::int64_t median_ns_ = 0;
  bool seeded_ = false;
};

// What an adaptive reader does next, and until when (CLOCK_MONOTONIC).
struct WakeStep {
  enum class Action {
    sleep,  // futex sleep until `until` (a publish wakes it earlier), then ask again
    spin,   // spin until `until` watching for the frame, then ask again
    block,  // the stream is not predictable now: plain futex sleep until a publish or the deadline
  };
  Action action = Action::block;
  std::int64_t until = 0;
};

// Places a short spin window around the next expected publish: the futex sleep ends `wake_margin`
// plus a jitter guard before it (a sleeping thread wakes late by the timer slack and, on a VM, by
// the wake-up of an idle vCPU), and the spin goes on after it for the rest of the spin budget.
// The window never takes more than `max_spin_share` of a period, so a reader spins at most that
// share of a core. When the budget is short (a large jitter), the guard shrinks so as much of the
// window lies after the expected publish as before it: frames come late more often than early
// (the writer's own timer wakes late), and a window that ends at the expected time misses half.
class WakePlanner {
 public:
  struct Params {
    std::int64_t wake_margin_ns = 80'000;  // how late a futex sleep with a deadline may wake
    std::int64_t min_guard_ns = 20'000;    // smallest guard band on either side of the publish
    int guard_jitters = 3;                 // guard = this many jitters (at least min_guard_ns)
    int max_spin_share_inverse = 25;       // spin at most period / this (4 % of a core)
    std::uint64_t min_frames = 4;          // frames of this writer before its period is trusted
    int max_jitter_share_inverse = 4;      // jitter above period / this: aperiodic, never spin
    int silent_after_periods = 4;          // no frame for this many periods: silent, never spin
  };

  WakePlanner() = default;
  explicit WakePlanner(const Params& params) noexcept : p_(params) {}

  // The step for a reader waiting at `now` with nothing deliverable; `wake_late_ns`: how late its
  // timed sleeps have been waking (WakeLateness), added to the wake margin when larger than it.
  WakeStep next(std::int64_t now, const StreamTiming& t, std::int64_t wake_late_ns = 0) const noexcept {
    const WakeStep block{WakeStep::Action::block, 0};
    if (!predictable(t)) return block;
    const std::int64_t since = now - t.latest_publish_ns;
    if (since < 0 || since > t.period_ns * p_.silent_after_periods) return block;
    const std::int64_t max_spin = t.period_ns / p_.max_spin_share_inverse;
    const std::int64_t margin = wake_late_ns > p_.wake_margin_ns ? wake_late_ns : p_.wake_margin_ns;
    std::int64_t guard = std::max(t.jitter_ns * p_.guard_jitters, p_.min_guard_ns);
    guard = std::min(guard, std::max<std::int64_t>(0, (max_spin - margin) / 2));
    const std::int64_t lead = guard + margin;  // the spin starts this long before the publish
    const std::int64_t tail = std::max(guard, max_spin - lead);  // and may go on this long after
    // The next expected publish whose spin window has not ended yet (a missed frame moves the
    // window on by whole periods, as the writer's clock does).
    const std::int64_t periods_past = since / t.period_ns;
    std::int64_t expected = t.latest_publish_ns + (periods_past + 1) * t.period_ns;
    if (expected - t.period_ns + tail > now && periods_past > 0) expected -= t.period_ns;
    const std::int64_t spin_from = expected - lead;
    std::int64_t spin_to = expected + tail;
    if (spin_to - spin_from > max_spin) spin_to = spin_from + max_spin;
    if (now < spin_from) return {WakeStep::Action::sleep, spin_from};
    if (now < spin_to) return {WakeStep::Action::spin, spin_to};
    // Past the window: the frame is late. Sleep on the futex until the next window opens.
    const std::int64_t next_from = spin_from + t.period_ns;
    return {WakeStep::Action::sleep, next_from};
  }

  // Whether the writer's timing is regular enough to predict at all.
  bool predictable(const StreamTiming& t) const noexcept {
    return t.period_ns > 0 && t.latest_publish_ns > 0 && t.frames_this_writer >= p_.min_frames &&
           t.jitter_ns * p_.max_jitter_share_inverse <= t.period_ns &&
           t.period_ns / p_.max_spin_share_inverse > 0;
  }

  const Params& params() const noexcept { return p_; }

 private:
  Params p_{};
};

// At most `limit` (<= kSpinLeases words) readers of a region spin at once. A lease word holds the
// time its spin ends: 0 or a time in the past is free, so a spinner that dies mid-spin never holds
// a lease for longer than its window.
class SpinLeases {
 public:
  // Takes a free lease until `until`; the index to release it, or -1 if none is free.
  static int acquire(std::atomic<std::int64_t>* leases, std::size_t limit, std::int64_t now,
                     std::int64_t until) noexcept {
    for (std::size_t i = 0; i < limit; ++i) {
      std::int64_t seen = leases[i].load(std::memory_order_relaxed);
      while (seen <= now) {
        if (leases[i].compare_exchange_weak(seen, until, std::memory_order_acq_rel)) {
          return static_cast<int>(i);
        }
      }
    }
    return -1;
  }
  // Gives the lease back early; a lease already expired and retaken by someone else is left alone.
  static void release(std::atomic<std::int64_t>* leases, int index, std::int64_t until) noexcept {
    if (index < 0) return;
    std::int64_t mine = until;
    leases[index].compare_exchange_strong(mine, 0, std::memory_order_acq_rel);
  }
};

}  // namespace sim::detail
