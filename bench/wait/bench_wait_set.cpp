// SPDX-License-Identifier: Apache-2.0
// bench_wait_set: what waiting on several streams at once costs, for each way SIM offers it.
//
// One writer process publishes small frames on K streams in turn, each stream at R frames/s
// (staggered, as unsynchronised sensors are). One reader process waits on all K streams and
// reads every frame; its latency is publish (writer's CLOCK_MONOTONIC stamp) → read, and its CPU
// is measured with getrusage. The ways of waiting, each in a fresh reader process:
//   futex_waitv   WaitSet, one futex_waitv sleep on every stream's word (Linux ≥ 5.16)
//   round_robin   WaitSet's fallback for older kernels (Jetson Orin's 5.15): sleeps on one
//                 stream at a time in 1 ms slices, checking all between slices
//   notifier      StreamNotifier's eventfd in the reader's own epoll loop (its helper thread
//                 waits with a WaitSet)
//   reader_wait   the reference: one stream at K×R frames/s and a plain blocking Reader::wait,
//                 i.e. the same number of wake-ups without any multi-stream machinery
// Strategies alternate within each run, so slow drifts of the machine hit them alike. Results
// are the mean over runs with a 95 % interval (Student t), and each strategy's mean and CPU
// as a ratio to reader_wait with its interval (delta method).
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <optional>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"
#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"

namespace {

constexpr std::size_t kPayloadBytes = 64;  // the cost of waking, not of copying

enum class Way { futex_waitv, round_robin, notifier, reader_wait };
constexpr std::array<Way, 4> kAllWays = {Way::futex_waitv, Way::round_robin, Way::notifier,
                                         Way::reader_wait};

const char* name_of(Way way) {
  switch (way) {
    case Way::futex_waitv: return "futex_waitv";
    case Way::round_robin: return "round_robin";
    case Way::notifier: return "notifier";
    case Way::reader_wait: return "reader_wait";
  }
  return "?";
}

// What one reader process measured; sent to the parent through a pipe as plain bytes.
struct RunResult {
  std::uint64_t frames = 0;
  std::uint64_t skipped = 0;
  std::uint64_t wakeups = 0;  // returns from the wait that found at least one frame
  double mean_us = 0;
  double p50_us = 0;
  double p99_us = 0;
  double max_us = 0;
  double cpu_us_per_frame = 0;
  int complete = 0;  // every stream's last frame arrived
  char strategy_used[16] = {};
};

double percentile(const std::vector<std::int64_t>& sorted, double p) {
  if (sorted.empty()) return 0;
  const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(sorted.size())));
  return static_cast<double>(sorted[std::min(sorted.size() - 1, rank == 0 ? 0 : rank - 1)]) / 1e3;
}

std::int64_t cpu_ns() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);  // every thread of the process, the notifier's included
  const auto ns = [](const timeval& t) { return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_usec * 1000; };
  return ns(usage.ru_utime) + ns(usage.ru_stime);
}

struct Config {
  unsigned streams = 4;
  double rate_hz = 100;
  unsigned frames = 500;  // per stream and run
  unsigned runs = 5;
  std::vector<std::string> ways;
  std::string json;
};

std::optional<std::vector<sim::Reader>> open_readers(const std::vector<std::string>& names) {
  std::vector<sim::Reader> readers;
  for (const auto& name : names) {
    auto reader = sim::Reader::open(name);
    if (!reader) {
      std::fprintf(stderr, "bench_wait_set: %s\n", reader.error().message.c_str());
      return std::nullopt;
    }
    readers.push_back(std::move(reader.value()));
  }
  return readers;
}

// The reader process's way of waiting, set up for its streams.
class Waiter {
 public:
  explicit Waiter(Way way) : way_(way), set_(options_of(way)) {}
  ~Waiter() {
    if (epoll_ >= 0) close(epoll_);
  }
  Waiter(const Waiter&) = delete;
  Waiter& operator=(const Waiter&) = delete;

  // False when the way cannot be set up for these streams (after a sentence on stderr, or none
  // when the WaitSet refuses a reader).
  bool prepare(std::vector<sim::Reader>& readers, const std::vector<std::string>& names) {
    if (way_ == Way::notifier) {
      auto opened = sim::StreamNotifier::open(names);
      if (!opened) {
        std::fprintf(stderr, "bench_wait_set: %s\n", opened.error().message.c_str());
        return false;
      }
      notifier_.emplace(std::move(opened.value()));
      epoll_ = epoll_create1(EPOLL_CLOEXEC);
      epoll_event event{};
      event.events = EPOLLIN;
      epoll_ctl(epoll_, EPOLL_CTL_ADD, notifier_->fd(), &event);
    } else if (way_ != Way::reader_wait) {
      for (auto& reader : readers) {
        if (!set_.add(reader)) return false;
      }
    }
    return true;
  }

  // Waits once and calls take(i) for every stream that may have a frame. Whether any take found
  // one; nothing when no frame came for 3 s (a silent writer ends the run, never hangs it).
  template <typename Take>
  std::optional<bool> wait(std::vector<sim::Reader>& readers, Take&& take) {
    constexpr auto kGiveUp = std::chrono::seconds(3);
    bool got = false;
    if (way_ == Way::reader_wait) {
      if (readers[0].wait(kGiveUp) != sim::ReadStatus::new_frame) return std::nullopt;
      got = take(0);
    } else if (way_ == Way::notifier) {
      epoll_event event{};
      if (epoll_wait(epoll_, &event, 1, 3000) != 1) return std::nullopt;
      const auto had = notifier_->drain();
      for (std::size_t i = 0; i < had.size(); ++i) {
        if (had[i]) got = take(i) || got;
      }
    } else {
      const auto ready_index = set_.wait(kGiveUp);
      if (!ready_index) return std::nullopt;
      for (std::size_t i = 0; i < readers.size(); ++i) got = take(i) || got;
    }
    return got;
  }

  // The strategy that ran (a WaitSet may fall back to round robin).
  const char* strategy_used() const {
    if (way_ == Way::reader_wait || way_ == Way::notifier) return name_of(way_);
    return set_.strategy() == sim::WaitSetStrategy::futex_waitv ? "futex_waitv" : "round_robin";
  }

 private:
  static sim::WaitSetOptions options_of(Way way) {
    sim::WaitSetOptions options;
    if (way == Way::round_robin) options.strategy = sim::WaitSetStrategy::round_robin;
    if (way == Way::futex_waitv) options.strategy = sim::WaitSetStrategy::futex_waitv;
    return options;
  }

  Way way_;
  sim::WaitSet set_;
  std::optional<sim::StreamNotifier> notifier_;
  int epoll_ = -1;
};

// The latency statistics of a run and its CPU per frame, into `result`.
void summarize(std::vector<std::int64_t>& latencies, std::int64_t cpu_used, RunResult& result) {
  result.frames = latencies.size();
  std::sort(latencies.begin(), latencies.end());
  double sum = 0;
  for (const auto v : latencies) sum += static_cast<double>(v);
  if (!latencies.empty()) {
    result.mean_us = sum / static_cast<double>(latencies.size()) / 1e3;
    result.p50_us = percentile(latencies, 50);
    result.p99_us = percentile(latencies, 99);
    result.max_us = static_cast<double>(latencies.back()) / 1e3;
    result.cpu_us_per_frame = static_cast<double>(cpu_used) / 1e3 / static_cast<double>(latencies.size());
  }
}

// The reader process: waits in `way` until every stream delivered its frame number `frames`.
RunResult read_all(Way way, const std::vector<std::string>& names, unsigned frames, int ready_fd) {
  RunResult result;
  auto opened = open_readers(names);
  if (!opened) return result;
  std::vector<sim::Reader>& readers = *opened;
  Waiter waiter(way);
  if (!waiter.prepare(readers, names)) return result;

  std::vector<std::int64_t> latencies;
  latencies.reserve(static_cast<std::size_t>(frames) * names.size());
  std::vector<std::uint64_t> last_seq(readers.size(), 0);
  std::array<std::byte, kPayloadBytes> buffer{};
  std::size_t finished = 0;
  // Reads every reader that has a frame; true when one was read.
  auto take = [&](std::size_t i) {
    sim::FrameInfo info;
    if (readers[i].read(buffer, info) != sim::ReadStatus::new_frame) return false;
    latencies.push_back(sim::monotonic_ns() - info.publish_ns);
    result.skipped += info.seq - last_seq[i] - 1;
    last_seq[i] = info.seq;
    if (info.seq == frames) ++finished;
    return true;
  };
  // The streams' frames published before this process started are not part of the run.
  for (std::size_t i = 0; i < readers.size(); ++i) {
    sim::FrameInfo info;
    (void)readers[i].read(buffer, info);
  }
  const std::int64_t cpu_start = cpu_ns();
  const char ready = 'r';
  if (write(ready_fd, &ready, 1) != 1) return result;
  while (finished < readers.size()) {
    const auto got = waiter.wait(readers, take);
    if (!got) break;
    if (*got) ++result.wakeups;
  }
  const std::int64_t cpu_used = cpu_ns() - cpu_start;
  result.complete = finished == readers.size() ? 1 : 0;
  std::snprintf(result.strategy_used, sizeof result.strategy_used, "%s", waiter.strategy_used());
  summarize(latencies, cpu_used, result);
  return result;
}

// One run of one way: the writer here, the reader in a child process.
std::optional<RunResult> run_once(Way way, const Config& config, unsigned run) {
  // reader_wait: one stream carrying every frame the others spread over K streams.
  const bool reference = way == Way::reader_wait;
  const unsigned streams = reference ? 1 : config.streams;
  const double stream_rate = reference ? config.rate_hz * config.streams : config.rate_hz;
  const unsigned frames = reference ? config.frames * config.streams : config.frames;
  std::vector<std::string> names;
  std::vector<sim::Writer> writers;
  for (unsigned i = 0; i < streams; ++i) {
    names.push_back("/bench_wait_set_" + std::to_string(getpid()) + "_" + std::to_string(run) + "_" +
                    std::to_string(i));
    sim::StreamSpec spec;
    spec.name = names.back();
    spec.capacity = kPayloadBytes;
    auto writer = sim::Writer::create(spec);
    if (!writer) {
      std::fprintf(stderr, "bench_wait_set: %s\n", writer.error().message.c_str());
      return std::nullopt;
    }
    writers.push_back(std::move(writer.value()));
  }
  auto remove_streams = [&] {
    writers.clear();
    for (const auto& name : names) (void)sim::destroy(name);
  };

  int ready[2];
  int results[2];
  if (pipe(ready) != 0 || pipe(results) != 0) return std::nullopt;
  const pid_t child = fork();
  if (child == 0) {
    close(ready[0]);
    close(results[0]);
    // No destructor of the parent's writers runs here: _exit below.
    const RunResult result = read_all(way, names, frames, ready[1]);
    const bool sent = write(results[1], &result, sizeof result) == static_cast<ssize_t>(sizeof result);
    _exit(sent ? 0 : 1);
  }
  close(ready[1]);
  close(results[1]);
  char byte = 0;
  const bool child_ready = child > 0 && read(ready[0], &byte, 1) == 1;

  std::array<std::byte, kPayloadBytes> payload{};
  if (child_ready) {
    // Absolute schedule: frame i of the whole run at start + i × (period / streams).
    const auto step_ns = static_cast<std::int64_t>(1e9 / stream_rate / streams);
    std::int64_t due = sim::monotonic_ns() + 20'000'000;
    for (unsigned i = 0; i < frames * streams; ++i) {
      const timespec at{static_cast<time_t>(due / 1'000'000'000), static_cast<long>(due % 1'000'000'000)};
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr);
      (void)writers[i % streams].write(payload, sim::realtime_ns());
      due += step_ns;
    }
  }
  RunResult result;
  const bool received = child_ready && read(results[0], &result, sizeof result) == static_cast<ssize_t>(sizeof result);
  close(ready[0]);
  close(results[0]);
  if (child > 0) waitpid(child, nullptr, 0);
  remove_streams();
  if (!received) {
    std::fprintf(stderr, "bench_wait_set: the %s reader process did not report.\n", name_of(way));
    return std::nullopt;
  }
  return result;
}

// Mean and the half-width of its 95 % interval over runs (Student t).
struct Estimate {
  double mean = 0;
  double half = 0;
  double se = 0;
};

Estimate estimate(const std::vector<double>& values) {
  static constexpr std::array<double, 10> t95 = {12.71, 4.30, 3.18, 2.78, 2.57, 2.45, 2.36, 2.31, 2.26, 2.23};
  Estimate e;
  if (values.empty()) return e;
  for (const double v : values) e.mean += v;
  e.mean /= static_cast<double>(values.size());
  if (values.size() < 2) return e;
  double squares = 0;
  for (const double v : values) squares += (v - e.mean) * (v - e.mean);
  e.se = std::sqrt(squares / static_cast<double>(values.size() - 1) / static_cast<double>(values.size()));
  const double t = values.size() - 1 <= t95.size() ? t95[values.size() - 2] : 1.96;
  e.half = t * e.se;
  return e;
}

// a / b with a 95 % interval by the delta method (normal approximation).
std::pair<double, double> ratio(const Estimate& a, const Estimate& b) {
  if (b.mean == 0) return {0, 0};
  const double r = a.mean / b.mean;
  const double relative = std::sqrt(std::pow(a.se / a.mean, 2) + std::pow(b.se / b.mean, 2));
  return {r, 1.96 * r * relative};
}

// The ways --ways names, in their fixed order; nothing when it names one that does not exist.
std::optional<std::vector<Way>> chosen_ways(const std::vector<std::string>& names) {
  std::vector<Way> ways;
  for (const Way way : kAllWays) {
    if (names.empty() || std::find(names.begin(), names.end(), name_of(way)) != names.end()) {
      ways.push_back(way);
    }
  }
  if (ways.size() != (names.empty() ? kAllWays.size() : names.size())) return std::nullopt;
  return ways;
}

// Every run of every way, a line each; nothing when a run failed or was incomplete.
std::optional<std::vector<std::vector<RunResult>>> measure(const std::vector<Way>& ways,
                                                           const Config& config) {
  std::printf("%u streams at %.0f Hz each (reader_wait: 1 stream at %.0f Hz), %u frames per stream, %u runs\n",
              config.streams, config.rate_hz, config.rate_hz * config.streams, config.frames, config.runs);
  std::printf("%-12s %3s %10s %9s %9s %9s %11s %8s %8s  %s\n", "way", "run", "frames", "mean_us",
              "p50_us", "p99_us", "cpu_us/frm", "skipped", "wakeups", "strategy");
  std::vector<std::vector<RunResult>> results(ways.size());
  for (unsigned run = 1; run <= config.runs; ++run) {
    for (std::size_t w = 0; w < ways.size(); ++w) {
      const auto result = run_once(ways[w], config, run);
      if (!result) return std::nullopt;
      std::printf("%-12s %3u %10llu %9.1f %9.1f %9.1f %11.2f %8llu %8llu  %s%s\n", name_of(ways[w]), run,
                  static_cast<unsigned long long>(result->frames), result->mean_us, result->p50_us,
                  result->p99_us, result->cpu_us_per_frame, static_cast<unsigned long long>(result->skipped),
                  static_cast<unsigned long long>(result->wakeups), result->strategy_used,
                  result->complete ? "" : "  INCOMPLETE");
      std::fflush(stdout);
      if (!result->complete) return std::nullopt;
      results[w].push_back(*result);
    }
  }
  return results;
}

// Prints the mean over runs of each way with its interval and its ratios to reader_wait, and
// returns the same as JSON.
std::string summarize_ways(const std::vector<Way>& ways,
                           const std::vector<std::vector<RunResult>>& results, const Config& config) {
  auto column = [&](std::size_t w, double RunResult::*field) {
    std::vector<double> values;
    for (const auto& r : results[w]) values.push_back(r.*field);
    return estimate(values);
  };
  const auto reference = std::find(ways.begin(), ways.end(), Way::reader_wait);
  std::printf("\nmean over runs [95 %% interval]; ratio to reader_wait (below 1: cheaper)\n");
  std::printf("%-12s %-22s %-22s %-22s %-18s %-18s\n", "way", "mean_us", "p99_us", "cpu_us/frame",
              "mean ratio", "cpu ratio");
  std::string json = "{\"streams\":" + std::to_string(config.streams) + ",\"rate_hz\":" +
                     std::to_string(config.rate_hz) + ",\"frames\":" + std::to_string(config.frames) +
                     ",\"runs\":" + std::to_string(config.runs) + ",\"ways\":[";
  for (std::size_t w = 0; w < ways.size(); ++w) {
    const auto mean = column(w, &RunResult::mean_us);
    const auto p99 = column(w, &RunResult::p99_us);
    const auto cpu = column(w, &RunResult::cpu_us_per_frame);
    std::string mean_ratio = "-", cpu_ratio = "-";
    std::pair<double, double> rm{0, 0}, rc{0, 0};
    if (reference != ways.end()) {
      const auto r = static_cast<std::size_t>(reference - ways.begin());
      rm = ratio(mean, column(r, &RunResult::mean_us));
      rc = ratio(cpu, column(r, &RunResult::cpu_us_per_frame));
      char text[64];
      std::snprintf(text, sizeof text, "%.2f ± %.2f", rm.first, rm.second);
      mean_ratio = text;
      std::snprintf(text, sizeof text, "%.2f ± %.2f", rc.first, rc.second);
      cpu_ratio = text;
    }
    char line[256];
    std::snprintf(line, sizeof line, "%-12s %8.1f [%5.1f, %5.1f] %8.1f [%5.1f, %5.1f] %6.2f [%5.2f, %5.2f] %-18s %-18s\n",
                  name_of(ways[w]), mean.mean, mean.mean - mean.half, mean.mean + mean.half, p99.mean,
                  p99.mean - p99.half, p99.mean + p99.half, cpu.mean, cpu.mean - cpu.half,
                  cpu.mean + cpu.half, mean_ratio.c_str(), cpu_ratio.c_str());
    std::fputs(line, stdout);
    char item[512];
    std::snprintf(item, sizeof item,
                  "%s{\"way\":\"%s\",\"mean_us\":%.3f,\"mean_ci95\":%.3f,\"p99_us\":%.3f,\"p99_ci95\":%.3f,"
                  "\"cpu_us_per_frame\":%.4f,\"cpu_ci95\":%.4f,\"mean_ratio\":%.4f,\"mean_ratio_ci95\":%.4f,"
                  "\"cpu_ratio\":%.4f,\"cpu_ratio_ci95\":%.4f}",
                  w == 0 ? "" : ",", name_of(ways[w]), mean.mean, mean.half, p99.mean, p99.half, cpu.mean,
                  cpu.half, rm.first, rm.second, rc.first, rc.second);
    json += item;
  }
  return json + "]}\n";
}

}  // namespace

int main(int argc, char** argv) {
  Config config;
  sim::apps::CommandLine cli(
      "bench_wait_set",
      "bench_wait_set: the cost of waiting on several SIM streams at once (WaitSet with "
      "futex_waitv, its round-robin fallback, StreamNotifier in epoll) against one blocking "
      "Reader::wait with the same number of wake-ups.");
  cli.add_option("--streams", config.streams, "streams the reader waits on").in_range(2u, 128u);
  cli.add_option("--rate", config.rate_hz, "frames per second on each stream").in_range(1.0, 2000.0);
  cli.add_option("--frames", config.frames, "frames per stream and run").in_range(10u, 100000u);
  cli.add_option("--runs", config.runs, "runs (each runs every way once, in turn)").in_range(1u, 100u);
  cli.add_option("--ways", config.ways, "futex_waitv, round_robin, notifier, reader_wait [all]")
      .delimiter(',');
  cli.add_option("--json", config.json, "also write the results here as JSON").type_name("FILE");
  if (const auto code = cli.parse(argc, argv)) return *code;
  const auto ways = chosen_ways(config.ways);
  if (!ways) {
    return cli.usage_error("--ways takes futex_waitv, round_robin, notifier and reader_wait, each once");
  }
  const auto results = measure(*ways, config);
  if (!results) return 1;
  const std::string json = summarize_ways(*ways, *results, config);
  if (!config.json.empty()) {
    std::FILE* out = std::fopen(config.json.c_str(), "w");
    if (out == nullptr || std::fputs(json.c_str(), out) < 0 || std::fclose(out) != 0) {
      return cli.fail("cannot write " + config.json + "; check the folder exists and is writable");
    }
  }
  return 0;
}
