// SPDX-License-Identifier: Apache-2.0
// What every soak reader checks about the frames it gets, and the "blocked reader missed the
// newest frame" measurement (docs in README.md, "Soak", and tests/soak/README.md).
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <chrono>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "sim/reader.hpp"
#include "soak_frames.hpp"

namespace soak {

inline std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// How long a thread has been runnable without running (the second field of schedstat): time a
// loaded machine, not the code under test, kept it from running.
class RunDelay {
 public:
  RunDelay() = default;
  explicit RunDelay(const std::string& path) : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {}
  RunDelay(RunDelay&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  RunDelay& operator=(RunDelay&& o) noexcept {
    std::swap(fd_, o.fd_);
    return *this;
  }
  RunDelay(const RunDelay&) = delete;
  RunDelay& operator=(const RunDelay&) = delete;
  ~RunDelay() {
    if (fd_ >= 0) ::close(fd_);
  }
  static RunDelay this_thread() { return RunDelay("/proc/thread-self/schedstat"); }
  static RunDelay of_process(int pid) {
    return RunDelay("/proc/" + std::to_string(pid) + "/schedstat");  // its main thread
  }
  // Nanoseconds, or -1 when unknown (no such process).
  std::int64_t now() const {
    if (fd_ < 0) return -1;
    char text[128];
    const ssize_t n = ::pread(fd_, text, sizeof text - 1, 0);
    if (n <= 0) return -1;
    text[n] = '\0';
    unsigned long long run = 0, delay = 0;
    if (std::sscanf(text, "%llu %llu", &run, &delay) != 2) return -1;
    return static_cast<std::int64_t>(delay);
  }

 private:
  int fd_ = -1;
};

// Time the hypervisor ran something else on this VM's CPUs ("steal", /proc/stat): threads that
// look running or asleep to the guest's scheduler do not run either. Sampled every 10 ms by one
// thread per process (reading /proc/stat costs ~0.1 ms); the value is the largest steal of any one
// CPU since the process started, in ns (the kernel counts it in 10 ms ticks).
class Steal {
 public:
  static std::int64_t now() {
    static Steal steal;
    return steal.ns_.load(std::memory_order_relaxed);
  }

 private:
  Steal() {
    std::thread([this] {
      const int fd = ::open("/proc/stat", O_RDONLY | O_CLOEXEC);
      std::vector<std::int64_t> first;
      for (;; std::this_thread::sleep_for(std::chrono::milliseconds(10))) {
        const auto per_cpu = read(fd);
        if (first.empty()) first = per_cpu;
        std::int64_t most = 0;
        for (std::size_t i = 0; i < per_cpu.size() && i < first.size(); ++i) {
          most = std::max(most, per_cpu[i] - first[i]);
        }
        ns_.store(most * 10'000'000, std::memory_order_relaxed);  // USER_HZ 100
      }
    }).detach();
  }
  // The steal ticks of each "cpuN" line.
  static std::vector<std::int64_t> read(int fd) {
    std::vector<std::int64_t> ticks;
    char text[4096];
    const ssize_t n = fd >= 0 ? ::pread(fd, text, sizeof text - 1, 0) : -1;
    if (n <= 0) return ticks;
    text[n] = '\0';
    for (const char* line = std::strstr(text, "\ncpu"); line != nullptr; line = std::strstr(line + 1, "\ncpu")) {
      long long f[8] = {};
      if (std::sscanf(line + 1, "cpu%*d %lld %lld %lld %lld %lld %lld %lld %lld", &f[0], &f[1], &f[2], &f[3],
                      &f[4], &f[5], &f[6], &f[7]) == 8) {
        ticks.push_back(f[7]);
      }
    }
    return ticks;
  }
  std::atomic<std::int64_t> ns_{0};
};

// Counters of one stream in one reader; printed as JSON by the agent.
struct StreamCounters {
  std::uint64_t frames = 0;
  std::uint64_t torn = 0;           // a delivered frame that fails its pattern (or checksum)
  std::uint64_t out_of_order = 0;   // a sequence number not above the previous one
  std::uint64_t missed = 0;         // blocked while a newer frame waited for more than 2 periods
  std::uint64_t timed = 0;          // deliveries the missed-newest measurement could time
  std::uint64_t untimed = 0;        // deliveries it could not: the publish time of the first
                                    // unseen frame unknown (a replay's frames skipped while
                                    // asleep), or the writer's process changed during the wait
  std::uint64_t skipped = 0;        // frames the writer published that this reader never got
                                    // (gaps in the numbering of one region's run; frames
                                    // published while the reader was not open are not counted)
  std::uint64_t lost = 0;           // of those, frames it slept through: skipped during a wait
                                    // that began before they were there, not explained by the
                                    // run delays (the rest: it was busy or kept from running)
  std::uint64_t overwritten = 0;    // borrowed frames the writer reused meanwhile (discarded)
  std::uint64_t reopens = 0;        // opened by name (first open included)
  std::uint64_t replacements = 0;   // regions replaced under the reader and followed
  std::int64_t worst_stall_ns = 0;  // the largest measured stall
};

// One delivery to check: the wait that preceded it and the frame it delivered.
struct Wait {
  std::int64_t start_ns = 0;           // when wait() was called
  std::int64_t end_ns = 0;             // when it returned
  std::int64_t own_delay_ns = 0;       // this thread's run delay during it
  std::int64_t writer_delay_ns = 0;    // the writer's main thread's run delay during it, 0 unknown
  std::int64_t steal_ns = 0;           // time the hypervisor took this VM's CPUs during it
  bool newer_at_start = false;         // a frame newer than the last delivered existed at start
  bool new_region = false;             // the reader followed the stream to a new region meanwhile
  bool writer_delay_known = false;     // the writer's process was known throughout the wait
};

// A reader asleep on a region that was replaced or removed looks for the new one once per slice
// of its wait (docs/protocol.md, "Waiting"): the first frame of a new region may come that much
// later, by design.
inline constexpr std::int64_t kRegionCheckSliceNs = 100'000'000;
// The longest a woken reader may take, net of run delays: two periods of a 30 Hz camera.
inline constexpr std::int64_t kLongestAllowanceNs = 66'666'667;

// The order and missed-newest bookkeeping of one stream (one region incarnation at a time).
class StreamCheck {
 public:
  StreamCheck(std::string name, std::int64_t period_ns) : name_(std::move(name)), period_ns_(period_ns) {}
  const std::string& name() const { return name_; }
  std::int64_t period_ns() const { return period_ns_; }
  // A region replaced under the same name (another layout, or removed and created anew): the
  // reader followed it. A replacing region carries the numbering on (docs/protocol.md), so the
  // order check goes on across it.
  void replaced() {
    std::lock_guard lock(mutex_);
    ++counters_.replacements;
  }
  // Opened by name (first, or again after the stream was removed and created anew): a new
  // region's numbering may start again.
  void restart() {
    std::lock_guard lock(mutex_);
    ++counters_.reopens;
    last_seq_ = 0;
    last_publish_ns_ = 0;
  }
  std::int64_t last_publish_ns() const { return last_publish_ns_; }
  std::uint64_t last_seq() const { return last_seq_; }

  // A frame delivered after `wait`. `carried_first_unseen` is the publish time of frame
  // last_seq+1 when the frame carries it (soak writer), else 0.
  void delivered(const sim::FrameInfo& info, bool whole, const Wait& wait,
                 std::int64_t carried_first_unseen) {
    std::lock_guard lock(mutex_);
    ++counters_.frames;
    if (!whole) report("torn", info.seq, 0);
    // Not above the previous number is out of order, unless published later: a stream removed
    // and created anew (sim_rm --dead, then a new writer) numbers from 1 again, and a reader
    // follows it to the new region.
    const bool new_stream = info.seq <= last_seq_ && info.publish_ns > last_publish_ns_;
    if (last_seq_ != 0 && info.seq <= last_seq_ && !new_stream) report("out_of_order", info.seq, 0);
    if (last_seq_ != 0 && info.seq > last_seq_) {
      count_skipped(info, wait);
      time_delivery(info, wait, carried_first_unseen);
    }
    last_seq_ = info.seq;
    last_publish_ns_ = info.publish_ns;
  }
  // wait() timed out although a frame newer than the last delivered had been published
  // `waiting_ns` before the timeout (net of run delays): a lost wake-up if over two periods (plus
  // one region-check slice if the reader followed the stream to a new region meanwhile).
  void timed_out_with_newer(std::int64_t waiting_ns, bool new_region) {
    std::lock_guard lock(mutex_);
    if (waiting_ns > allowed(new_region)) {
      counters_.worst_stall_ns = std::max(counters_.worst_stall_ns, waiting_ns);
      report("missed", 0, waiting_ns);
    }
  }
  void torn_checksum(std::uint64_t seq) {
    std::lock_guard lock(mutex_);
    report("torn", seq, 0);
  }
  void overwritten() {
    std::lock_guard lock(mutex_);
    ++counters_.overwritten;
  }
  StreamCounters snapshot() const {
    std::lock_guard lock(mutex_);
    return counters_;
  }

 private:
  // Frames skipped by design (the reader takes the newest: it was busy, or a loaded machine kept
  // it or the writer from running) or slept through (lost). Lost: the wait began with nothing
  // newer there, the delivered frame was published before the wait ended (not while the reader
  // was already awake), the reader did not follow the stream to a new region, and the run
  // delays and steal during the wait cover less than three quarters of the skipped frames'
  // periods.
  void count_skipped(const sim::FrameInfo& info, const Wait& wait) {
    const std::uint64_t skipped = info.seq - last_seq_ - 1;
    counters_.skipped += skipped;
    if (skipped == 0 || wait.newer_at_start || wait.new_region || info.publish_ns > wait.end_ns) return;
    const std::int64_t kept_from_running = wait.own_delay_ns + wait.writer_delay_ns + wait.steal_ns;
    if (4 * kept_from_running < 3 * static_cast<std::int64_t>(skipped) * period_ns_) counters_.lost += skipped;
  }
  void time_delivery(const sim::FrameInfo& info, const Wait& wait, std::int64_t carried) {
    std::int64_t became_readable = 0;  // when frame last_seq+1 was published
    if (wait.newer_at_start) {
      became_readable = wait.start_ns;  // it was there already: the wait must return at once
    } else if (info.seq == last_seq_ + 1) {
      became_readable = info.publish_ns;
    } else if (carried > 0) {
      became_readable = carried;
    } else {
      ++counters_.untimed;
      return;
    }
    if (!wait.writer_delay_known) {  // a writer just restarted: its scheduling is unknown
      ++counters_.untimed;
      return;
    }
    ++counters_.timed;
    const std::int64_t stall = wait.end_ns - std::max(wait.start_ns, became_readable) -
                               wait.own_delay_ns - wait.writer_delay_ns - wait.steal_ns;
    counters_.worst_stall_ns = std::max(counters_.worst_stall_ns, stall);
    if (stall > allowed(wait.new_region)) report("missed", info.seq, stall, &wait, became_readable);
  }
  // Two periods, but never more than two camera periods: a LiDAR's 200 ms would hide a reader
  // that is never woken and finds frames only at its 100 ms region checks.
  std::int64_t allowed(bool new_region) const {
    return std::min(2 * period_ns_, kLongestAllowanceNs) + (new_region ? kRegionCheckSliceNs : 0);
  }
  // One line at once (a reader killed later has told it already); for a stall, the wait's parts.
  void report(const char* what, std::uint64_t seq, std::int64_t stall_ns, const Wait* wait = nullptr,
              std::int64_t readable_ns = 0) {
    if (what[0] == 't') ++counters_.torn;
    if (what[0] == 'o') ++counters_.out_of_order;
    if (what[0] == 'm') ++counters_.missed;
    auto ms = [](std::int64_t ns) { return static_cast<double>(ns) / 1e6; };
    // For a stall, its moments on CLOCK_MONOTONIC (shared by every process of the machine): the
    // soak compares them with the other readers' stalls and the writer's publish gaps.
    char parts[384] = "";
    if (wait != nullptr) {
      std::snprintf(parts, sizeof parts,
                    ",\"wait_ms\":%.3f,\"own_run_delay_ms\":%.3f,\"writer_run_delay_ms\":%.3f,"
                    "\"steal_ms\":%.3f,\"writer_delay_known\":%s,\"new_region\":%s,\"readable_ns\":%" PRId64
                    ",\"end_ns\":%" PRId64,
                    ms(wait->end_ns - wait->start_ns), ms(wait->own_delay_ns), ms(wait->writer_delay_ns),
                    ms(wait->steal_ns),
                    wait->writer_delay_known ? "true" : "false", wait->new_region ? "true" : "false",
                    std::max(wait->start_ns, readable_ns), wait->end_ns);
    }
    std::printf("{\"kind\":\"violation\",\"what\":\"%s\",\"stream\":\"%s\",\"seq\":%" PRIu64
                ",\"last_seq\":%" PRIu64 ",\"stall_ms\":%.3f,\"period_ms\":%.3f%s}\n",
                what, name_.c_str(), seq, last_seq_, ms(stall_ns), ms(period_ns_), parts);
    std::fflush(stdout);
  }

  std::string name_;
  std::int64_t period_ns_;
  mutable std::mutex mutex_;
  StreamCounters counters_;
  std::uint64_t last_seq_ = 0;
  std::int64_t last_publish_ns_ = 0;
};

}  // namespace soak
