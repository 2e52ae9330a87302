// SPDX-License-Identifier: Apache-2.0
// sim_bench: SIM side by side with iceoryx, Fast DDS and Cyclone DDS, and the memcpy floor, on
// the SIM paper's workloads (issue 5). One program; the writer and every reader are separate
// processes: sim_bench starts itself again with a hidden --role argument for each of them.
//
// One configuration and run goes like this:
//   1. the writer process sets up its transport and prints "ready";
//   2. the reader processes subscribe, wait until they are connected, and print "ready";
//   3. sim_bench sends "go": the writer waits for DDS matching, then publishes `frames` frames
//      at `rate` Hz, stamping CLOCK_MONOTONIC into each frame immediately before publishing;
//   4. each reader stamps when it holds the whole payload, and at the end prints its counts,
//      its CPU time and its latencies; sim_bench pools them per configuration into one CSV row.
#include <signal.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/clock.hpp"
#include "sim/os.hpp"
#include "sim/reader.hpp"
#include "stats.hpp"
#include "transport.hpp"

using namespace sim::bench;
using namespace std::chrono_literals;

namespace {

// ---------------------------------------------------------------------------------------------
// Shared by the roles

struct Usage {
  double cpu_s = 0;
  long voluntary_switches = 0;
  long involuntary_switches = 0;
};

Usage usage_now() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  Usage u;
  u.cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
            static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) / 1e6;
  u.voluntary_switches = ru.ru_nvcsw;
  u.involuntary_switches = ru.ru_nivcsw;
  return u;
}

Usage usage_since(const Usage& start) {
  const Usage now = usage_now();
  return {now.cpu_s - start.cpu_s, now.voluntary_switches - start.voluntary_switches,
          now.involuntary_switches - start.involuntary_switches};
}

// Reads every byte of a frame once, so a zero-copy reader pays for touching the payload like a
// copying one does. The sum goes to a volatile sink so the compiler cannot drop the loop.
std::atomic<std::uint64_t> checksum_sink{0};
std::uint64_t checksum(std::span<const std::byte> bytes) {
  std::uint64_t sum = 0;
  const std::size_t words = bytes.size() / 8;
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t w;
    std::memcpy(&w, bytes.data() + i * 8, 8);
    sum += w;
  }
  for (std::size_t i = words * 8; i < bytes.size(); ++i) sum += static_cast<std::uint8_t>(bytes[i]);
  checksum_sink.store(sum, std::memory_order_relaxed);
  return sum;
}

// Evicts a buffer from every cache level (x86 clflush; elsewhere by sweeping a buffer larger
// than any last-level cache), so the next access comes from memory.
void flush_from_caches(std::span<const std::byte> bytes) {
#if defined(__x86_64__) || defined(__i386__)
  for (std::size_t i = 0; i < bytes.size(); i += 64) __builtin_ia32_clflush(bytes.data() + i);
  if (!bytes.empty()) __builtin_ia32_clflush(bytes.data() + bytes.size() - 1);
  __builtin_ia32_mfence();
#else
  static std::vector<std::byte> sweep(256u << 20);
  static std::byte value{0};
  value = static_cast<std::byte>(static_cast<unsigned>(value) + 1);
  for (std::size_t i = 0; i < sweep.size(); i += 64) sweep[i] = value;
  (void)bytes;
#endif
}

void sleep_until_ns(std::int64_t t) {
  timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Pins and raises the calling process as asked; failures are reported, not fatal.
void place_self(int cpu, int rt_priority) {
  if (cpu >= 0) {
    if (auto pinned = sim::pin_current_thread(cpu); !pinned) {
      std::fprintf(stderr, "sim_bench: cannot pin to CPU %d: %s\n", cpu, pinned.error().message.c_str());
    }
  }
  if (rt_priority > 0) {
    if (auto raised = sim::set_realtime_priority(rt_priority); !raised) {
      std::fprintf(stderr, "sim_bench: cannot use SCHED_FIFO: %s\n", raised.error().message.c_str());
    }
  }
}

struct RoleOptions {
  std::string role;
  std::string transport;
  std::string topic;
  std::size_t payload = 0;
  int readers = 1;
  int index = 0;
  int domain = 0;
  std::uint64_t frames = 0;
  std::uint64_t warmup = 0;
  double rate = 0;  // 0: as fast as possible
  double jitter = 0;  // each period is drawn uniformly from period * (1 ± jitter)
  double pause_s = 0;  // > 0: the writer falls silent this long halfway through the measured frames
  double idle_s = 0;  // > 0: the idle-cost run (the writer publishes nothing for this long)
  int cpu = -1;
  int rt_priority = 0;
};

Endpoint endpoint_of(const RoleOptions& o) {
  return {o.topic, o.payload, o.readers, o.domain, o.role == "reader" ? o.index : -1};
}

// ---------------------------------------------------------------------------------------------
// Writer role

int run_writer(const RoleOptions& o, Transport t) {
  place_self(o.cpu, o.rt_priority);
  std::string error;
  auto publisher = make_publisher(t, endpoint_of(o), error);
  if (!publisher) {
    std::printf("error=%s\n", error.c_str());
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);
  std::string line;
  if (!std::getline(std::cin, line) || line != "go") return 1;
  if (!publisher->wait_for_readers(o.readers, 30s)) {
    std::printf("error=the readers did not connect to the writer within 30 s\n");
    std::fflush(stdout);
    return 1;
  }
  // The writer's frame: arbitrary content, the header and tail are sealed per frame.
  std::vector<std::byte> frame(o.payload);
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = static_cast<std::byte>(i * 131 + 7);

  const std::int64_t period_ns = o.rate > 0 ? static_cast<std::int64_t>(1e9 / o.rate) : 0;
  // --jitter: a sensor whose frames come at irregular intervals (fixed seed: runs compare).
  std::mt19937_64 random(12345);
  std::uniform_real_distribution<double> deviation(-o.jitter, o.jitter);
  const Usage start = usage_now();
  const std::int64_t t0 = sim::monotonic_ns();
  std::int64_t next = t0;
  std::uint64_t published = 0;
  const std::uint64_t frames = o.idle_s > 0 ? 0 : o.frames;  // idle cost: a silent writer
  // --pause: a sensor that stops for seconds (unplugged, a replay held) and then resumes.
  const std::uint64_t pause_after = o.warmup + (frames - std::min(frames, o.warmup)) / 2;
  for (std::uint64_t seq = 1; seq <= frames; ++seq) {
    if (publisher->publish(frame, seq)) ++published;
    if (o.pause_s > 0 && seq == pause_after) {
      next += static_cast<std::int64_t>(o.pause_s * 1e9);
      sleep_until_ns(next);
    }
    if (period_ns > 0) {
      const double scale = o.jitter > 0 ? 1.0 + deviation(random) : 1.0;
      next += static_cast<std::int64_t>(static_cast<double>(period_ns) * scale);  // absolute: no drift
      sleep_until_ns(next);
    }
  }
  const double duration = static_cast<double>(sim::monotonic_ns() - t0) / 1e9;
  const Usage used = usage_since(start);
  std::printf("result published=%" PRIu64 " cpu_s=%.6f nvcsw=%ld nivcsw=%ld duration_s=%.3f path=%s\n",
              published, used.cpu_s, used.voluntary_switches, used.involuntary_switches, duration,
              publisher->path_note().empty() ? "-" : publisher->path_note().c_str());
  std::fflush(stdout);
  // Stay until the readers are done: a DDS writer that leaves takes its samples with it.
  std::getline(std::cin, line);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Reader role

// Idle cost: waits for frames that never come, as a program does between bursts, and prints
// the CPU that took.
int run_idle_reader(const RoleOptions& o, SubscriberBackend& subscriber) {
  const Usage start = usage_now();
  const std::int64_t end = sim::monotonic_ns() + static_cast<std::int64_t>(o.idle_s * 1e9);
  std::uint64_t received = 0;
  while (sim::monotonic_ns() < end) {
    const Delivery d = subscriber.receive(100ms);
    if (d.kind == Delivery::Kind::frame) {
      ++received;
      (void)subscriber.release();
    }
  }
  const Usage used = usage_since(start);
  std::printf("result received=%" PRIu64 " gaps=0 torn=0 invalidated=0 last=0 cpu_s=%.6f nvcsw=%ld "
              "nivcsw=%ld\nlat\n",
              received, used.cpu_s, used.voluntary_switches, used.involuntary_switches);
  std::fflush(stdout);
  return 0;
}

// What a measuring reader counts.
struct ReaderTally {
  std::vector<std::int64_t> latencies;
  std::uint64_t last = 0, received = 0, gaps = 0, torn = 0, invalidated = 0;
  std::int64_t last_frame_at = 0;
};

// Takes one delivered frame: checks that it is whole and new, counts the frames replaced before
// it, and notes its latency when it is past the warm-up.
// `zero_copy`: the subscriber's, asked once (a virtual call would add to every latency).
void take_frame(const RoleOptions& o, SubscriberBackend& subscriber, bool zero_copy,
                const Delivery& d, ReaderTally& t) {
  if (zero_copy) checksum(d.bytes);
  const std::int64_t stamp = sim::monotonic_ns();  // the reader holds the whole payload
  FrameHeader header{};
  std::uint64_t tail = ~0ull;
  if (d.bytes.size() >= kMinPayload) {
    std::memcpy(&header, d.bytes.data(), sizeof(header));
    std::memcpy(&tail, d.bytes.data() + d.bytes.size() - sizeof(tail), sizeof(tail));
  }
  if (!subscriber.release()) {  // overwritten while we read it: not delivered
    ++t.invalidated;
    return;
  }
  if (header.size != d.bytes.size() || tail != header.seq || header.seq == 0) {
    ++t.torn;
    return;
  }
  if (header.seq <= t.last) return;  // an old frame again: not new, not counted
  // Frames between the last delivered one and this one were replaced before we took them.
  const std::uint64_t gap_from = std::max(t.last, o.warmup);
  if (header.seq > gap_from + 1) t.gaps += header.seq - gap_from - 1;
  if (header.seq > o.warmup) {
    t.latencies.push_back(stamp - header.stamp_ns);
    ++t.received;
  }
  t.last = header.seq;
  t.last_frame_at = stamp;
}

void print_reader_result(const ReaderTally& t, const Usage& used,
                         const SubscriberBackend& subscriber) {
  std::printf("result received=%" PRIu64 " gaps=%" PRIu64 " torn=%" PRIu64 " invalidated=%" PRIu64
              " last=%" PRIu64 " cpu_s=%.6f nvcsw=%ld nivcsw=%ld caught_spinning=%" PRIu64
              " spin_s=%.6f\n",
              t.received, t.gaps, t.torn, t.invalidated, t.last, used.cpu_s,
              used.voluntary_switches, used.involuntary_switches,
              subscriber.frames_caught_spinning(), subscriber.spin_s());
  std::string lat = "lat";
  for (const auto v : t.latencies) lat += " " + std::to_string(v);
  std::printf("%s\n", lat.c_str());
  std::fflush(stdout);
}

int run_reader(const RoleOptions& o, Transport t) {
  place_self(o.cpu, o.rt_priority);
  std::string error;
  auto subscriber = make_subscriber(t, endpoint_of(o), error);
  if (!subscriber) {
    std::printf("error=%s\n", error.c_str());
    return 1;
  }
  if (!subscriber->ready(30s)) {
    std::printf("error=the reader did not connect to the writer within 30 s\n");
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);
  if (o.idle_s > 0) return run_idle_reader(o, *subscriber);

  ReaderTally tally;
  tally.latencies.reserve(o.frames);
  const std::int64_t period_ns = o.rate > 0 ? static_cast<std::int64_t>(1e9 / o.rate) : 0;
  const std::int64_t idle_limit_ns = std::max<std::int64_t>(3'000'000'000, 50 * period_ns) +
                                     static_cast<std::int64_t>(o.pause_s * 1e9);
  const std::int64_t first_deadline = sim::monotonic_ns() + 60'000'000'000;
  const Usage start = usage_now();
  const bool zero_copy = subscriber->zero_copy();
  while (tally.last < o.frames) {
    const Delivery d = subscriber->receive(100ms);
    if (d.kind == Delivery::Kind::error) {
      std::printf("error=%s\n", d.error.c_str());
      return 1;
    }
    if (d.kind == Delivery::Kind::none) {
      const std::int64_t now = sim::monotonic_ns();
      if (tally.last == 0 ? now > first_deadline : now - tally.last_frame_at > idle_limit_ns) break;
      continue;
    }
    take_frame(o, *subscriber, zero_copy, d, tally);
  }
  print_reader_result(tally, usage_since(start), *subscriber);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Orchestrator

// Set by SIGINT/SIGTERM: the run stops at the next step and cleans up (children, RouDi).
volatile std::sig_atomic_t stop_requested = 0;
extern "C" void request_stop(int) { stop_requested = 1; }

struct Options {
  std::vector<std::string> transports{"sim-poll", "sim-block", "sim-zero", "sim-adaptive", "sim-zero-adaptive", "iceoryx", "fastdds",
                                      "cyclone"};
  std::vector<std::size_t> payloads{25920, 1382400, 921600, 6912000};
  std::vector<int> readers{1, 10};
  double rate = 100;
  double jitter = 0;
  double pause_s = 0;
  double idle_s = 0;
  double vehicle_s = 0;  // > 0: the many-stream vehicle workload for this many seconds
  bool max_rate = false;
  std::uint64_t frames = 1100;
  std::uint64_t warmup = 100;
  int runs = 5;
  std::string csv;
  bool quick = false;
  std::vector<int> cpus;
  int rt_priority = 0;
  bool no_floor = false;
  bool skip_missing = false;
};

struct Row {
  std::string transport;
  std::size_t payload = 0;
  int readers = 0;
  int run = 0;
  LatencySummary lat;
  std::uint64_t received = 0, skipped = 0, lost = 0, torn = 0, published = 0;
  double writer_cpu_s = 0, reader_cpu_s = 0;
  long writer_nvcsw = 0, writer_nivcsw = 0, reader_nvcsw = 0, reader_nivcsw = 0;
  long long udp_datagrams = -1;
  std::uint64_t caught_spinning = 0;  // adaptive readers: frames that arrived while they spun
  double spin_s = 0;                  // and the time they spent spinning, all readers
  std::string path;
  std::string status = "ok";
};

std::string self_exe() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string("sim_bench");
}

// UDP datagrams sent plus received on this machine so far (/proc/net/snmp, IPv4 and IPv6).
long long udp_datagrams() {
  long long total = 0;
  bool found = false;
  std::ifstream snmp("/proc/net/snmp");
  std::string header, values;
  while (std::getline(snmp, header) && std::getline(snmp, values)) {
    if (header.rfind("Udp:", 0) != 0) continue;
    std::istringstream hs(header), vs(values);
    std::string key, value;
    hs >> key;
    vs >> value;
    while (hs >> key && vs >> value) {
      if (key == "InDatagrams" || key == "OutDatagrams") {
        total += std::stoll(value);
        found = true;
      }
    }
  }
  std::ifstream snmp6("/proc/net/snmp6");
  std::string key;
  long long value = 0;
  while (snmp6 >> key >> value) {
    if (key == "Udp6InDatagrams" || key == "Udp6OutDatagrams") total += value;
  }
  return found ? total : -1;
}

std::map<std::string, std::string> fields(const std::string& line) {
  std::map<std::string, std::string> out;
  std::istringstream in(line);
  std::string word;
  while (in >> word) {
    const auto eq = word.find('=');
    if (eq != std::string::npos) out[word.substr(0, eq)] = word.substr(eq + 1);
  }
  return out;
}

// Waits for a child's "ready" line; other lines (library chatter) are passed to stderr.
bool await_ready(ChildProcess& child, const std::string& who, std::string& error) {
  for (;;) {
    auto l = child.line(90s);
    if (!l) {
      error = who + (child.timed_out() ? " did not get ready within 90 s" : " exited before it was ready");
      return false;
    }
    if (*l == "ready") return true;
    if (l->rfind("error=", 0) == 0) {
      error = who + ": " + l->substr(6);
      return false;
    }
    std::fprintf(stderr, "  [%s] %s\n", who.c_str(), l->c_str());
  }
}

// A SIM transport leaves a region behind when its writer had to be killed.
bool is_sim_transport(const std::string& transport) { return transport.rfind("sim-", 0) == 0; }

// Removes the SIM regions of a run when it ends. Declared before the run's processes, so it runs
// after they are gone: a SIM writer that had to be killed cannot remove its region itself.
struct RegionSweep {
  std::vector<std::string> names;
  ~RegionSweep() {
    for (const auto& name : names) (void)sim::destroy(name, /*force=*/true);
  }
};

// The writer and reader processes of one run. The readers go first when it is destroyed.
struct RoleProcesses {
  std::vector<std::unique_ptr<ChildProcess>> writers;
  std::vector<std::unique_ptr<ChildProcess>> readers;

  // Tells the writers to leave, then waits for everyone; a process that stays is killed.
  void stop() {
    for (auto& w : writers) w->send("stop");
    for (auto& w : writers) {
      if (w->wait(30s) < 0) w->signal(SIGKILL);
    }
    for (auto& r : readers) {
      if (r->wait(10s) < 0) r->signal(SIGKILL);
    }
  }
};

// What a writer prints when it has published everything ("result published=… cpu_s=… …").
struct WriterReport {
  std::uint64_t published = 0;
  double cpu_s = 0;
  long nvcsw = 0, nivcsw = 0;
  std::string path;
};

// Waits up to `budget` for each line of the writer's report; other lines (library chatter) go to
// stderr as `who`'s. nullopt, with `error`, when the writer reports an error, dies or is late.
std::optional<WriterReport> read_writer_report(ChildProcess& writer, const std::string& who,
                                               std::chrono::milliseconds budget, std::string& error) {
  for (;;) {
    auto l = writer.line(budget);
    if (!l) {
      error = writer.timed_out() ? "the writer did not finish in time" : "the writer died";
      return std::nullopt;
    }
    if (l->rfind("error=", 0) == 0) {
      error = "writer: " + l->substr(6);
      return std::nullopt;
    }
    if (l->rfind("result ", 0) == 0) {
      auto f = fields(*l);
      return WriterReport{std::stoull(f["published"]), std::stod(f["cpu_s"]), std::stol(f["nvcsw"]),
                          std::stol(f["nivcsw"]), f["path"]};
    }
    std::fprintf(stderr, "  [%s] %s\n", who.c_str(), l->c_str());
  }
}

// What a reader prints when it stops: its "result" line and its "lat" line of latencies.
struct ReaderReport {
  std::uint64_t received = 0, gaps = 0, torn = 0;
  double cpu_s = 0;
  long nvcsw = 0, nivcsw = 0;
  std::uint64_t caught_spinning = 0;  // adaptive readers only
  double spin_s = 0;                  // likewise
  std::vector<std::int64_t> latencies;
};

ReaderReport parse_reader_result(const std::string& line) {
  auto f = fields(line);
  ReaderReport report;
  report.received = std::stoull(f["received"]);
  report.gaps = std::stoull(f["gaps"]);
  report.torn = std::stoull(f["torn"]);
  report.cpu_s = std::stod(f["cpu_s"]);
  report.nvcsw = std::stol(f["nvcsw"]);
  report.nivcsw = std::stol(f["nivcsw"]);
  if (f.count("caught_spinning") != 0) report.caught_spinning = std::stoull(f["caught_spinning"]);
  if (f.count("spin_s") != 0) report.spin_s = std::stod(f["spin_s"]);
  return report;
}

// Reads a reader's report (it stops at the last frame or after an idle timeout); other lines go
// to stderr as `who`'s. nullopt, with `error`, when it reports an error or gives no result.
std::optional<ReaderReport> read_reader_report(ChildProcess& reader, const std::string& who,
                                               std::string& error) {
  std::optional<ReaderReport> report;
  std::vector<std::int64_t> latencies;
  bool got_lat = false;
  while (!(report && got_lat)) {
    auto l = reader.line(120s);
    if (!l) break;
    if (l->rfind("error=", 0) == 0) {
      error = "reader: " + l->substr(6);
      return std::nullopt;
    }
    if (l->rfind("result ", 0) == 0) {
      report = parse_reader_result(*l);
    } else if (l->rfind("lat", 0) == 0) {
      std::istringstream in(l->substr(3));
      std::int64_t v;
      while (in >> v) latencies.push_back(v);
      got_lat = true;
    } else {
      std::fprintf(stderr, "  [%s] %s\n", who.c_str(), l->c_str());
    }
  }
  if (!report) {
    error = who + " gave no result";
    return std::nullopt;
  }
  report->latencies = std::move(latencies);
  return report;
}

// Adds one reader's report to the row of its run; `expected`: the frames past the warm-up.
void add_reader_report(const ReaderReport& report, std::uint64_t expected, Row& row) {
  row.received += report.received;
  // Gaps are frames a newer one replaced (by design). Torn frames show up as gaps too but count
  // as lost, like frames after the last one delivered, which never arrived.
  const std::uint64_t skipped = report.gaps - std::min(report.gaps, report.torn);
  row.skipped += skipped;
  row.lost += expected - std::min(expected, report.received + skipped);
  row.torn += report.torn;
  row.reader_cpu_s += report.cpu_s;
  row.reader_nvcsw += report.nvcsw;
  row.reader_nivcsw += report.nivcsw;
  row.caught_spinning += report.caught_spinning;
  row.spin_s += report.spin_s;
}

// One stream of the vehicle workload, with a writer and a reader of its own.
struct VehicleStream {
  const char* what;
  std::size_t payload;
  double rate;
};

// The vehicle of the SIM paper: 7 cameras of 1920x1200x3 B at 30 Hz and a LiDAR at 10 Hz.
std::vector<VehicleStream> vehicle_streams() {
  std::vector<VehicleStream> streams(7, VehicleStream{"camera", 1920 * 1200 * 3, 30.0});
  streams.push_back({"lidar", 1382400, 10.0});
  return streams;
}

// Gives `flag` the value `value` in a role's argument list.
void set_argument(std::vector<std::string>& args, const std::string& flag, const std::string& value) {
  for (std::size_t a = 0; a + 1 < args.size(); ++a) {
    if (args[a] == flag) args[a + 1] = value;
  }
}

// The grid's table on stdout: a header, then a line per row.
void print_row_header() {
  std::printf("%-10s %9s %3s %3s %10s %10s %10s %10s %10s %8s %7s %5s\n", "transport", "payload",
              "R", "run", "min_us", "mean_us", "p99_us", "p999_us", "max_us", "received",
              "skipped", "lost");
}

void print_row(const Row& r) {
  std::printf("%-10s %9zu %3d %3d %10.1f %10.1f %10.1f %10.1f %10.1f %8" PRIu64 " %7" PRIu64
              " %5" PRIu64 "%s\n",
              r.transport.c_str(), r.payload, r.readers, r.run, r.lat.min_us, r.lat.mean_us,
              r.lat.p99_us, r.lat.p999_us, r.lat.max_us, r.received, r.skipped, r.lost,
              r.status == "ok" ? "" : ("  " + r.status).c_str());
  std::fflush(stdout);
}

// --csv: one row per transport x payload x readers x run in the file given, and the further
// columns of the same row in *_extra.csv next to it. Each row is flushed: a run stopped early
// keeps the rows so far.
class CsvFiles {
 public:
  CsvFiles() = default;
  CsvFiles(const CsvFiles&) = delete;
  CsvFiles& operator=(const CsvFiles&) = delete;
  ~CsvFiles() {
    if (csv_ != nullptr) std::fclose(csv_);
    if (extra_ != nullptr) std::fclose(extra_);
  }

  // Creates both files with their header lines; false when one cannot be written.
  bool open(const std::string& path) {
    csv_ = std::fopen(path.c_str(), "w");
    std::string extra_path = path;
    if (extra_path.size() > 4 && extra_path.ends_with(".csv")) extra_path.resize(extra_path.size() - 4);
    extra_path += "_extra.csv";
    extra_ = std::fopen(extra_path.c_str(), "w");
    if (csv_ == nullptr || extra_ == nullptr) return false;
    std::fprintf(csv_, "transport,payload_bytes,readers,run,min_us,mean_us,p50_us,p95_us,p99_us,"
                       "p999_us,max_us,std_us,received,skipped,lost,writer_cpu_s,reader_cpu_s\n");
    std::fprintf(extra_, "transport,payload_bytes,readers,run,published,torn,writer_nvcsw,"
                         "writer_nivcsw,reader_nvcsw,reader_nivcsw,udp_datagrams,path,status,"
                         "rate_hz,frames,warmup,cpus,rt_priority,jitter,pause_s,caught_spinning,spin_s\n");
    return true;
  }

  // One row in each file (nothing when no files are open); `o`: the run's settings.
  void write(const Row& r, const Options& o) {
    if (csv_ == nullptr) return;
    std::fprintf(csv_, "%s,%zu,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%" PRIu64 ",%" PRIu64
                       ",%" PRIu64 ",%.6f,%.6f\n",
                 r.transport.c_str(), r.payload, r.readers, r.run, r.lat.min_us, r.lat.mean_us,
                 r.lat.p50_us, r.lat.p95_us, r.lat.p99_us, r.lat.p999_us, r.lat.max_us, r.lat.std_us,
                 r.received, r.skipped, r.lost, r.writer_cpu_s, r.reader_cpu_s);
    std::string cpus;
    for (const int c : o.cpus) {
      if (!cpus.empty()) cpus += ' ';
      cpus += std::to_string(c);
    }
    std::fprintf(extra_, "%s,%zu,%d,%d,%" PRIu64 ",%" PRIu64 ",%ld,%ld,%ld,%ld,%lld,%s,%s,%g,%" PRIu64
                         ",%" PRIu64 ",%s,%d,%g,%g,%" PRIu64 ",%.6f\n",
                 r.transport.c_str(), r.payload, r.readers, r.run, r.published, r.torn,
                 r.writer_nvcsw, r.writer_nivcsw, r.reader_nvcsw, r.reader_nivcsw, r.udp_datagrams,
                 r.path.empty() ? "-" : r.path.c_str(), r.status.c_str(), o.max_rate ? 0.0 : o.rate,
                 o.frames, o.warmup, cpus.empty() ? "-" : cpus.c_str(), o.rt_priority, o.jitter, o.pause_s,
                 r.caught_spinning, r.spin_s);
    std::fflush(csv_);
    std::fflush(extra_);
  }

 private:
  std::FILE* csv_ = nullptr;
  std::FILE* extra_ = nullptr;
};

class Bench {
 public:
  explicit Bench(Options o) : o_(std::move(o)), exe_(self_exe()) {}

  std::vector<std::string> role_args(const std::string& role, const std::string& transport,
                                     const std::string& topic, std::size_t payload, int readers,
                                     int index) const {
    std::vector<std::string> a{exe_,
                               "--role", role,
                               "--role-transport", transport,
                               "--role-topic", topic,
                               "--role-payload", std::to_string(payload),
                               "--role-readers", std::to_string(readers),
                               "--role-index", std::to_string(index),
                               "--role-domain", std::to_string(domain_),
                               "--frames", std::to_string(o_.frames),
                               "--warmup", std::to_string(o_.warmup),
                               "--rate", std::to_string(o_.max_rate ? 0.0 : o_.rate),
                               "--jitter", std::to_string(o_.jitter),
                               "--pause", std::to_string(o_.pause_s),
                               "--idle-cost", std::to_string(o_.idle_s),
                               "--rt-priority", std::to_string(o_.rt_priority)};
    const int cpu = cpu_for(role == "writer" ? -1 : index);
    if (cpu >= 0) {
      a.push_back("--role-cpu");
      a.push_back(std::to_string(cpu));
    }
    return a;
  }

  // The writer takes the first CPU of --cpu; readers share the others (all of them if only one).
  int cpu_for(int reader_index) const {
    if (o_.cpus.empty()) return -1;
    if (reader_index < 0 || o_.cpus.size() == 1) return o_.cpus.front();
    const std::size_t others = o_.cpus.size() - 1;
    return o_.cpus[1 + static_cast<std::size_t>(reader_index) % others];
  }

  // A topic no other run of this or another sim_bench uses.
  std::string next_topic() { return "simbench_" + std::to_string(getpid()) + "_" + std::to_string(counter_++); }

  // Starts the writer and waits until it is ready, then starts `readers` readers and waits for
  // each. false, with `error`, when one does not start or get ready.
  bool start_roles(const std::string& transport, const std::string& topic, std::size_t payload,
                   int readers, RoleProcesses& processes, std::string& error) {
    auto& writer = *processes.writers.emplace_back(
        std::make_unique<ChildProcess>(role_args("writer", transport, topic, payload, readers, 0)));
    if (!writer.started()) {
      error = "cannot start the writer process";
      return false;
    }
    if (!await_ready(writer, "writer", error)) return false;
    for (int i = 0; i < readers; ++i) {
      processes.readers.push_back(std::make_unique<ChildProcess>(
          role_args("reader", transport, topic, payload, readers, i)));
      if (!processes.readers.back()->started()) {
        error = "cannot start a reader process";
        return false;
      }
    }
    for (int i = 0; i < readers; ++i) {
      if (!await_ready(*processes.readers[static_cast<std::size_t>(i)], "reader " + std::to_string(i), error)) {
        return false;
      }
    }
    return true;
  }

  // How long the writer of a run may take to publish everything: twice its schedule, plus 2 min.
  std::chrono::milliseconds run_budget() const {
    const double period_s = o_.max_rate ? 0.0 : 1.0 / o_.rate;
    return std::chrono::milliseconds(
        static_cast<long long>((static_cast<double>(o_.frames) * period_s + o_.pause_s) * 1000.0 * 2) + 120'000);
  }

  // One configuration, one run: a writer and `readers` reader processes; the pooled row.
  Row run_one(const std::string& transport, std::size_t payload, int readers, int run) {
    Row row;
    row.transport = transport;
    row.payload = payload;
    row.readers = readers;
    row.run = run;
    const std::string topic = next_topic();
    const long long udp_before = udp_datagrams();
    RegionSweep sweep;
    if (is_sim_transport(transport)) sweep.names.push_back("/" + topic);
    auto fail = [&](const std::string& why) {
      row.status = "failed";
      if (stop_requested) return row;
      std::fprintf(stderr, "sim_bench: %s %zu B %dR run %d failed: %s\n", transport.c_str(),
                   payload, readers, run, why.c_str());
      return row;
    };

    RoleProcesses processes;
    std::string error;
    if (!start_roles(transport, topic, payload, readers, processes, error)) return fail(error);
    ChildProcess& writer = *processes.writers.front();
    writer.send("go");
    const auto written = read_writer_report(writer, "writer", run_budget(), error);
    if (!written) return fail(error);
    row.published = written->published;
    row.writer_cpu_s = written->cpu_s;
    row.writer_nvcsw = written->nvcsw;
    row.writer_nivcsw = written->nivcsw;
    row.path = written->path;
    std::vector<std::int64_t> pooled;
    for (int i = 0; i < readers; ++i) {
      auto read = read_reader_report(*processes.readers[static_cast<std::size_t>(i)],
                                     "reader " + std::to_string(i), error);
      if (!read) return fail(error);
      add_reader_report(*read, o_.frames - o_.warmup, row);
      pooled.insert(pooled.end(), read->latencies.begin(), read->latencies.end());
    }
    processes.stop();
    const long long udp_after = udp_datagrams();
    if (udp_before >= 0 && udp_after >= 0) row.udp_datagrams = udp_after - udp_before;
    row.lat = summarize(std::move(pooled));
    if (row.received == 0) row.status = "no_frames";
    return row;
  }

  // The floor: what a writer and a reader at least pay to move the payload through memory. A
  // writer thread copies it into a slot, a reader thread (on the other core when the scheduler
  // allows) copies it out; the sample is the sum of the two copy times, without the hand-over
  // between them. Before each frame the source, the slot and the destination are flushed from
  // the caches ("cold": at 100 Hz on a busy machine, the transports' buffers are cold too), and
  // the reader fetches what another core wrote, as in the transports.
  Row memcpy_floor(std::size_t payload, int run) {
    Row row;
    row.transport = "memcpy";
    row.payload = payload;
    row.readers = 1;
    row.run = run;
    const std::size_t slots = 2;  // a double buffer
    std::vector<std::byte> src(payload), dst(payload), shm(slots * payload);
    for (std::size_t i = 0; i < src.size(); ++i) src[i] = static_cast<std::byte>(i);
    std::memset(shm.data(), 1, shm.size());
    std::memset(dst.data(), 2, dst.size());
    std::vector<std::int64_t> samples;
    samples.reserve(o_.frames);
    std::atomic<std::uint64_t> written{0}, read{0};
    std::atomic<std::int64_t> write_ns{0};
    const Usage start = usage_now();
    std::thread reader([&] {
      for (std::uint64_t i = 1; i <= o_.frames; ++i) {
        // Sleep, not spin: on 2 shared cores a spinning thread would preempt the writer's copy.
        for (std::uint64_t w; (w = written.load(std::memory_order_acquire)) < i;) written.wait(w);
        const std::byte* slot = shm.data() + ((i - 1) % slots) * payload;
        const std::int64_t t0 = sim::monotonic_ns();
        std::memcpy(dst.data(), slot, payload);
        asm volatile("" ::: "memory");
        const std::int64_t t1 = sim::monotonic_ns();
        if (i > o_.warmup) samples.push_back(write_ns.load(std::memory_order_relaxed) + (t1 - t0));
        read.store(i, std::memory_order_release);
        read.notify_one();
      }
    });
    for (std::uint64_t i = 1; i <= o_.frames; ++i) {
      std::byte* slot = shm.data() + ((i - 1) % slots) * payload;
      flush_from_caches(src);
      flush_from_caches({slot, payload});
      flush_from_caches(dst);
      const std::int64_t t0 = sim::monotonic_ns();
      std::memcpy(slot, src.data(), payload);
      asm volatile("" ::: "memory");
      write_ns.store(sim::monotonic_ns() - t0, std::memory_order_relaxed);
      written.store(i, std::memory_order_release);
      written.notify_one();
      for (std::uint64_t r; (r = read.load(std::memory_order_acquire)) < i;) read.wait(r);
    }
    reader.join();
    const Usage used = usage_since(start);
    checksum(dst);
    row.writer_cpu_s = used.cpu_s;
    row.received = samples.size();
    row.published = o_.frames;
    row.lat = summarize(std::move(samples));
    return row;
  }

  // The vehicle of the SIM paper: every stream at its own rate at once, a reader each.
  int vehicle(const std::vector<Transport>& transports) {
    const std::vector<VehicleStream> streams = vehicle_streams();
    std::printf("%-18s %3s %-7s %9s %6s %10s %10s %8s %5s\n", "transport", "run", "stream", "payload",
                "Hz", "mean_us", "p99_us", "received", "lost");
    int failures = 0;
    for (const Transport t : transports) {
      for (int run = 1; run <= o_.runs && !stop_requested; ++run) {
        if (!vehicle_run(std::string(to_string(t)), run, streams)) ++failures;
      }
    }
    return failures == 0 ? 0 : 1;
  }

  // The writer's arguments for one vehicle stream: its own rate, and --vehicle seconds of frames
  // of which the first second is the warm-up.
  std::vector<std::string> vehicle_writer_args(const std::string& transport, const std::string& topic,
                                               const VehicleStream& stream) const {
    auto args = role_args("writer", transport, topic, stream.payload, 1, 0);
    set_argument(args, "--rate", std::to_string(stream.rate));
    set_argument(args, "--frames", std::to_string(static_cast<std::uint64_t>(o_.vehicle_s * stream.rate)));
    set_argument(args, "--warmup", std::to_string(static_cast<std::uint64_t>(stream.rate)));
    return args;
  }

  // Starts each stream's writer, waiting until it is ready before the next, and its reader; then
  // waits for the readers. false, with `error` when there is one, when a process does not start.
  bool start_vehicle(const std::string& transport, const std::vector<VehicleStream>& streams,
                     std::vector<std::string>& topics, RegionSweep& sweep, RoleProcesses& processes,
                     std::string& error) {
    for (const auto& stream : streams) {
      topics.push_back(next_topic());
      if (is_sim_transport(transport)) sweep.names.push_back("/" + topics.back());
      auto args = vehicle_writer_args(transport, topics.back(), stream);
      auto& writer = *processes.writers.emplace_back(std::make_unique<ChildProcess>(args));
      if (!writer.started() || !await_ready(writer, "writer " + topics.back(), error)) return false;
      set_argument(args, "--role", "reader");  // the same settings, the writer's CPU included
      processes.readers.push_back(std::make_unique<ChildProcess>(args));
    }
    for (std::size_t i = 0; i < processes.readers.size(); ++i) {
      ChildProcess& reader = *processes.readers[i];
      if (!reader.started() || !await_ready(reader, "reader " + topics[i], error)) return false;
    }
    return true;
  }

  // One vehicle run on one transport: a line per stream, then the CPU of all its processes.
  // false when its processes did not start.
  bool vehicle_run(const std::string& transport, int run, const std::vector<VehicleStream>& streams) {
    std::vector<std::string> topics;
    RegionSweep sweep;
    RoleProcesses processes;
    std::string error;
    if (!start_vehicle(transport, streams, topics, sweep, processes, error)) {
      std::fprintf(stderr, "sim_bench: vehicle %s run %d failed: %s\n", transport.c_str(), run, error.c_str());
      return false;
    }
    for (auto& w : processes.writers) w->send("go");
    double cpu_s = 0;
    const auto budget = std::chrono::milliseconds(static_cast<long long>(o_.vehicle_s * 2000) + 120'000);
    for (std::size_t i = 0; i < processes.writers.size(); ++i) {
      // A writer that fails adds no CPU; its reader's line shows what it missed.
      const auto written = read_writer_report(*processes.writers[i], "writer " + topics[i], budget, error);
      if (written) cpu_s += written->cpu_s;
    }
    for (std::size_t i = 0; i < processes.readers.size(); ++i) {
      const ReaderReport read =
          read_reader_report(*processes.readers[i], "reader " + topics[i], error).value_or(ReaderReport{});
      cpu_s += read.cpu_s;
      print_vehicle_stream(transport, run, streams[i], read);
    }
    processes.stop();
    std::printf("%-18s %3d total CPU of 8 writers + 8 readers: %.2f s over %.0f s = %.1f %% of one core\n",
                transport.c_str(), run, cpu_s, o_.vehicle_s, 100.0 * cpu_s / o_.vehicle_s);
    std::fflush(stdout);
    return true;
  }

  void print_vehicle_stream(const std::string& transport, int run, const VehicleStream& stream,
                            const ReaderReport& read) const {
    const auto expected = static_cast<std::uint64_t>(o_.vehicle_s * stream.rate) -
                          static_cast<std::uint64_t>(stream.rate);
    const LatencySummary sum = summarize(read.latencies);
    std::printf("%-18s %3d %-7s %9zu %6.0f %10.1f %10.1f %8" PRIu64 " %5" PRIu64 "\n", transport.c_str(),
                run, stream.what, stream.payload, stream.rate, sum.mean_us, sum.p99_us, read.received,
                expected - std::min(expected, read.received + read.gaps));
  }

  // The idle cost: per transport, the CPU its readers use while no frame comes.
  int idle_cost(const std::vector<Transport>& transports) {
    const int readers = o_.readers.front();
    std::printf("%-18s %3s %8s %14s %16s\n", "transport", "R", "seconds", "readers_cpu_s",
                "%_of_one_core");
    int failures = 0;
    for (const Transport t : transports) {
      for (int run = 1; run <= o_.runs && !stop_requested; ++run) {
        const Row row = run_one(std::string(to_string(t)), o_.payloads.front(), readers, run);
        if (row.status == "failed") {
          ++failures;
          continue;
        }
        std::printf("%-18s %3d %8.1f %14.3f %16.2f\n", std::string(to_string(t)).c_str(), readers,
                    o_.idle_s, row.reader_cpu_s, 100.0 * row.reader_cpu_s / o_.idle_s);
        std::fflush(stdout);
      }
    }
    return failures == 0 ? 0 : 1;
  }

  // The transports and payloads asked for, checked: nullopt (after one sentence) when one is
  // unknown, missing from this build, or a payload is too small.
  std::optional<std::vector<Transport>> checked_transports() {
    std::vector<Transport> transports;
    for (const auto& name : o_.transports) {
      Transport t;
      if (!parse_transport(name, t)) {
        std::fprintf(stderr, "sim_bench: unknown transport '%s': use sim-poll, sim-block, sim-zero, "
                             "sim-adaptive, sim-zero-adaptive, sim-poll-described, iceoryx, fastdds or "
                             "cyclone.\n", name.c_str());
        return std::nullopt;
      }
      if (!available(t)) {
        if (o_.skip_missing) {
          std::fprintf(stderr, "sim_bench: %s is not in this build; skipped.\n", name.c_str());
          continue;
        }
        std::fprintf(stderr, "sim_bench: %s is not in this build: install its Debian package "
                             "(scripts/deps/bench.txt), reconfigure, or pass --skip-missing.\n",
                     name.c_str());
        return std::nullopt;
      }
      transports.push_back(t);
    }
    for (const auto p : o_.payloads) {
      if (p < kMinPayload) {
        std::fprintf(stderr, "sim_bench: payload %zu B is below the %zu B frame header; use a larger one.\n",
                     p, kMinPayload);
        return std::nullopt;
      }
    }
    return transports;
  }

  int run_all() {
    const auto checked = checked_transports();
    if (!checked) return 2;
    const std::vector<Transport>& transports = *checked;
    domain_ = static_cast<int>(getpid() % 200) + 1;

    std::unique_ptr<ChildProcess> roudi;
    // Stops RouDi on every way out, so its shared memory never outlives the run.
    struct RoudiStop {
      Bench& bench;
      std::unique_ptr<ChildProcess>& roudi;
      ~RoudiStop() {
        if (roudi) bench.stop_roudi(*roudi);
      }
    } roudi_stop{*this, roudi};
    if (std::any_of(transports.begin(), transports.end(), needs_roudi)) {
      std::string error;
      roudi = start_roudi(error);
      if (!roudi) {
        std::fprintf(stderr, "sim_bench: %s\n", error.c_str());
        return 1;
      }
    }

    if (o_.idle_s > 0) return idle_cost(transports);
    if (o_.vehicle_s > 0) return vehicle(transports);
    return grid(transports);
  }

  // The latency grid: every transport x payload x readers, run after run, after the memcpy floor;
  // a line per row on stdout, and a row in the CSV files when asked for.
  int grid(const std::vector<Transport>& transports) {
    CsvFiles files;
    if (!o_.csv.empty() && !files.open(o_.csv)) {
      std::fprintf(stderr, "sim_bench: cannot write %s: check the folder exists and is writable.\n",
                   o_.csv.c_str());
      return 1;
    }
    const std::size_t total = o_.payloads.size() * o_.readers.size() * static_cast<std::size_t>(o_.runs) *
                              (transports.size() + (o_.no_floor ? 0 : 1));
    std::size_t done = 0;
    int failures = 0;
    print_row_header();
    auto emit = [&](const Row& r) {
      ++done;
      print_row(r);
      if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\r[%zu/%zu]   ", done, total);
      if (r.status == "failed") ++failures;
      files.write(r, o_);
    };

    // Runs are the outer loop so slow drift of the machine touches every transport alike.
    for (int run = 1; run <= o_.runs && !stop_requested; ++run) {
      for (const auto payload : o_.payloads) {
        for (const int readers : o_.readers) {
          if (!o_.no_floor && readers == o_.readers.front() && !stop_requested) {
            emit(memcpy_floor(payload, run));
          }
          for (const auto t : transports) {
            if (stop_requested) break;
            emit(run_one(std::string(to_string(t)), payload, readers, run));
          }
        }
      }
    }
    if (stop_requested) std::fprintf(stderr, "sim_bench: stopped by a signal; the CSV holds the rows so far.\n");
    if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
    return failures == 0 && !stop_requested ? 0 : 1;
  }

  // RouDi, iceoryx's daemon, with memory pools for every payload and reader count of this run.
  std::unique_ptr<ChildProcess> start_roudi(std::string& error) {
    const char* roudi_path = "/usr/bin/iox-roudi";
    if (access(roudi_path, X_OK) != 0) {
      error = "iox-roudi is missing: apt-get install iceoryx (see scripts/deps/bench.txt).";
      return nullptr;
    }
    if (access("/dev/shm/iceoryx_mgmt", F_OK) == 0) {
      error = "another iceoryx RouDi seems to be running (/dev/shm/iceoryx_mgmt exists): stop it, "
              "or remove the stale file if none runs, then retry.";
      return nullptr;
    }
    roudi_config_ = "/tmp/sim_bench_roudi_" + std::to_string(getpid()) + ".toml";
    std::ofstream cfg(roudi_config_);
    const int max_readers = *std::max_element(o_.readers.begin(), o_.readers.end());
    cfg << "[general]\nversion = 1\n\n[[segment]]\n\n";
    // Small pools for the peers' own bookkeeping, then one pool per payload with room for every
    // reader's queue, the samples in use, and Cyclone's extra header.
    std::map<std::size_t, int> pools{{128, 10000}, {1024, 5000}, {16384, 1000}, {131072, 200}};
    for (const auto p : o_.payloads) {
      const std::size_t size = (p + 1024 + 7) / 8 * 8;
      pools[size] = std::max(pools[size], 4 * max_readers + 16);
    }
    for (const auto& [size, count] : pools) {
      cfg << "[[segment.mempool]]\nsize = " << size << "\ncount = " << count << "\n\n";
    }
    cfg.close();
    // Its output goes to a log file: nobody reads its pipe during the run, and a full pipe
    // would stall it.
    roudi_log_ = "/tmp/sim_bench_roudi_" + std::to_string(getpid()) + ".log";
    auto roudi = std::make_unique<ChildProcess>(std::vector<std::string>{
        "/bin/sh", "-c",
        std::string("exec ") + roudi_path + " -c " + roudi_config_ + " -m off -l warning >" +
            roudi_log_ + " 2>&1"});
    if (!roudi->started()) {
      error = "cannot start iox-roudi.";
      return nullptr;
    }
    // RouDi says nothing at log level warning; it is up once its management segment exists.
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    // (/tmp/roudi is the socket applications register through.)
    while (access("/dev/shm/iceoryx_mgmt", F_OK) != 0 || access("/tmp/roudi", F_OK) != 0) {
      if (roudi->wait(0ms) >= 0 || std::chrono::steady_clock::now() > deadline) {
        error = "iox-roudi did not start: see " + roudi_log_ + ".";
        return nullptr;
      }
      std::this_thread::sleep_for(20ms);
    }
    std::this_thread::sleep_for(300ms);  // the segment exists a moment before RouDi listens
    return roudi;
  }

  void stop_roudi(ChildProcess& roudi) {
    roudi.signal(SIGINT);
    if (roudi.wait(15s) < 0) roudi.signal(SIGKILL);
    roudi.wait(5s);
    std::remove(roudi_config_.c_str());
    std::remove(roudi_log_.c_str());
  }

 private:
  Options o_;
  std::string exe_;
  int domain_ = 0;
  int counter_ = 0;
  std::string roudi_config_;
  std::string roudi_log_;
};

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// The command line as given: the options, the hidden role, and the lists still as text.
struct Arguments {
  Options o;
  RoleOptions role;
  std::string transports = "sim-poll,sim-block,sim-zero,sim-adaptive,sim-zero-adaptive,iceoryx,fastdds,cyclone";
  std::string payloads = "25920,1382400,921600,6912000";
  std::string readers = "1,10";
  std::string cpus;
  bool list = false;
};

void add_options(sim::apps::CommandLine& cli, Arguments& a) {
  Options& o = a.o;
  cli.add_option("--transports", a.transports,
                 "comma list of sim-poll,sim-block,sim-zero,iceoryx,fastdds,cyclone");
  cli.add_option("--payloads", a.payloads, "comma list of payload sizes in bytes");
  cli.add_option("--readers", a.readers, "comma list of reader counts (one process each)");
  cli.add_option("--rate", o.rate, "frames per second the writer publishes (0: as fast as it can)")
      .non_negative();
  cli.add_flag("--max-rate", o.max_rate, "publish as fast as the writer can instead of --rate");
  cli.add_option("--jitter", o.jitter, "draw each publish period from period x (1 ± this), e.g. 0.1 "
                                       "for ±10 %: an irregular sensor")
      .in_range(0.0, 0.9);
  cli.add_option("--pause", o.pause_s, "the writer falls silent for this many seconds halfway "
                                       "through each run, then resumes: readers must stay correct "
                                       "and cheap across it (reader CPU includes the pause)")
      .in_range(0.0, 60.0);
  cli.add_option("--vehicle", o.vehicle_s, "instead of the payload grid: the many-stream vehicle "
                                          "workload for this many seconds (7 camera streams of "
                                          "1920x1200x3 B at 30 Hz + one 1,382,400 B LiDAR stream "
                                          "at 10 Hz, a reader each), per transport")
      .in_range(0.0, 3600.0);
  cli.add_option("--idle-cost", o.idle_s, "instead of latency: the CPU the readers (first --readers "
                                          "value) use over this many seconds while the writer "
                                          "publishes nothing, per transport")
      .in_range(0.0, 3600.0);
  cli.add_option("--frames", o.frames, "frames per run, warm-up included");
  cli.add_option("--warmup", o.warmup, "first frames of each run left out of the statistics");
  cli.add_option("--runs", o.runs, "runs per configuration").positive();
  cli.add_option("--csv", o.csv, "write one row per transport x payload x readers x run here "
                                 "(and the extra columns next to it, as *_extra.csv)");
  cli.add_flag("--quick", o.quick, "smoke test: 60 frames (10 warm-up), 1 run");
  cli.add_option("--cpu", a.cpus, "comma list of CPUs: the writer pins to the first, readers to the rest");
  cli.add_option("--rt-priority", o.rt_priority, "run writer and readers under SCHED_FIFO at this "
                                                  "priority (1-99, needs root)")
      .in_range(0, 99);
  cli.add_flag("--no-floor", o.no_floor, "do not measure the memcpy floor");
  cli.add_flag("--list-transports", a.list, "print the transports this build has, one a line, and exit");
  cli.add_flag("--skip-missing", o.skip_missing, "leave out transports this build does not have "
                                                  "instead of failing");
  // The roles sim_bench starts itself in; hidden from --help.
  RoleOptions& role = a.role;
  cli.add_option("--role", role.role, "").hidden().one_of({"writer", "reader"});
  cli.add_option("--role-transport", role.transport, "").hidden();
  cli.add_option("--role-topic", role.topic, "").hidden();
  cli.add_option("--role-payload", role.payload, "").hidden();
  cli.add_option("--role-readers", role.readers, "").hidden();
  cli.add_option("--role-index", role.index, "").hidden();
  cli.add_option("--role-domain", role.domain, "").hidden();
  cli.add_option("--role-cpu", role.cpu, "").hidden();
}

// This process as the writer or a reader of one run, with the run's settings.
int run_role(RoleOptions role, const Options& o) {
  Transport t;
  if (!parse_transport(role.transport, t)) return 2;
  role.frames = o.frames;
  role.warmup = o.warmup;
  role.rate = o.rate;
  role.jitter = o.jitter;
  role.pause_s = o.pause_s;
  role.idle_s = o.idle_s;
  role.rt_priority = o.rt_priority;
  return role.role == "writer" ? run_writer(role, t) : run_reader(role, t);
}

void list_transports() {
  for (const auto t : {Transport::sim_poll, Transport::sim_block, Transport::sim_zero,
                       Transport::sim_adaptive, Transport::sim_zero_adaptive,
                       Transport::sim_poll_described, Transport::iceoryx, Transport::fastdds, Transport::cyclone}) {
    if (available(t)) std::printf("%s\n", std::string(to_string(t)).c_str());
  }
}

// The lists read into `a.o` and the options checked together; false (after one sentence on
// stderr) when they are wrong.
bool complete_options(Arguments& a) {
  Options& o = a.o;
  o.transports = split_list(a.transports);
  o.payloads.clear();
  o.readers.clear();
  try {
    for (const auto& p : split_list(a.payloads)) o.payloads.push_back(std::stoull(p));
    for (const auto& r : split_list(a.readers)) o.readers.push_back(std::stoi(r));
    for (const auto& c : split_list(a.cpus)) o.cpus.push_back(std::stoi(c));
  } catch (const std::exception&) {
    std::fprintf(stderr, "sim_bench: --payloads, --readers and --cpu take comma lists of numbers, "
                         "e.g. --payloads 25920,921600.\n");
    return false;
  }
  if (o.transports.empty() || o.payloads.empty() || o.readers.empty() ||
      std::any_of(o.readers.begin(), o.readers.end(), [](int r) { return r < 1 || r > 64; })) {
    std::fprintf(stderr, "sim_bench: give at least one transport, payload and reader count "
                         "(1-64 readers).\n");
    return false;
  }
  if (o.quick) {
    o.frames = 60;
    o.warmup = 10;
    o.runs = 1;
  }
  if (o.rate <= 0) o.max_rate = true;
  if (o.warmup >= o.frames) {
    std::fprintf(stderr, "sim_bench: --warmup must be smaller than --frames.\n");
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_bench",
      "sim_bench: SIM against iceoryx, Fast DDS, Cyclone DDS and the memcpy floor, one writer and "
      "N reader processes per configuration (issue 5).");
  Arguments arguments;
  add_options(cli, arguments);
  if (const auto code = cli.parse(argc, argv)) return *code;
  if (!arguments.role.role.empty()) return run_role(arguments.role, arguments.o);
  if (arguments.list) {
    list_transports();
    return 0;
  }
  if (!complete_options(arguments)) return 2;
  struct sigaction sa{};
  sa.sa_handler = request_stop;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  ChildProcess::set_stop_flag(&stop_requested);
  return Bench(std::move(arguments.o)).run_all();
}
