// SPDX-License-Identifier: Apache-2.0
// sim_test_peer: the other process in multi-process tests. Prints key=value lines on stdout.
//
//   writer NAME FRAMES RATE_HZ MIN_BYTES MAX_BYTES LINGER_MS   publish pattern frames
//   reader NAME UNTIL_SEQ TIMEOUT_MS MODE                       MODE: wait | poll | borrow |
//                                                               adaptive | spin (WaitMode::poll) |
//                                                               adaptive-one-core (pinned to 1 CPU)
//   waitset NAMES UNTIL_SEQ TIMEOUT_MS STRATEGY                 NAMES comma-separated; STRATEGY:
//                                                               futex_waitv | round_robin; one
//                                                               WaitSet until every stream reaches
//                                                               UNTIL_SEQ; a summary line per stream
//   hold NAME                                                   own the stream until killed
//   remove NAME                                                 destroy() the stream until SIGTERM
//   stall-in-copy NAME                                          stop inside read()'s copy of a frame
//   hold-borrow NAME                                            borrow a frame and keep it
//   recalibrate NAME                                            frame 1 described as camera_a; once
//                                                               a reader sleeps, describe camera_b
//                                                               and publish frame 2
//   open-at-once PREFIX COUNT                                   open PREFIX_0 … PREFIX_<COUNT-1> the
//                                                               moment each appears; count those
//                                                               without writer or description yet
#include <sched.h>
#if defined(__has_feature)
#if __has_feature(address_sanitizer) && !defined(__SANITIZE_ADDRESS__)
#define __SANITIZE_ADDRESS__ 1  // clang says it this way, GCC the other
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#endif
#include <signal.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"
#include "sim_test/frames.hpp"

using namespace sim;
using namespace std::chrono_literals;

namespace {

int run_writer(const std::string& name, std::uint64_t frames, double rate_hz, std::size_t min_bytes,
               std::size_t max_bytes, long linger_ms) {
  auto writer = Writer::create({.name = name, .capacity = max_bytes});
  if (!writer) {
    std::printf("error=%s\n", writer.error().message.c_str());
    return 1;
  }
  std::printf("ready first=%llu pid=%d\n", static_cast<unsigned long long>(writer->last_seq() + 1),
              getpid());
  std::fflush(stdout);
  const std::int64_t period_ns = rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0;
  std::int64_t next = monotonic_ns();
  for (std::uint64_t i = 0; i < frames; ++i) {
    const std::uint64_t seq = writer->last_seq() + 1;
    Loan loan = writer->loan();
    const std::size_t size = test::frame_size(seq, min_bytes, max_bytes);
    test::fill_frame(loan.bytes().first(size), seq);
    if (std::move(loan).commit(size, realtime_ns()) != WriteStatus::ok) return 1;
    if (period_ns > 0) {
      next += period_ns;  // absolute schedule: no drift
      timespec ts{next / 1'000'000'000, next % 1'000'000'000};
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    }
  }
  std::printf("done last=%llu\n", static_cast<unsigned long long>(writer->last_seq()));
  std::fflush(stdout);
  std::this_thread::sleep_for(std::chrono::milliseconds(linger_ms));
  return 0;
}

int run_reader(const std::string& name, std::uint64_t until_seq, long timeout_ms,
               const std::string& mode) {
  const std::int64_t deadline = monotonic_ns() + timeout_ms * 1'000'000;
  ReaderOptions options;
  if (mode == "adaptive-one-core") {
    cpu_set_t one;
    CPU_ZERO(&one);
    cpu_set_t all;
    if (sched_getaffinity(0, sizeof all, &all) != 0) return 1;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(cpu, &all)) {
        CPU_SET(cpu, &one);
        break;
      }
    }
    if (sched_setaffinity(0, sizeof one, &one) != 0) return 1;
  }
  if (mode.starts_with("adaptive")) options.wait_mode = WaitMode::adaptive;
  if (mode == "spin") options.wait_mode = WaitMode::poll;
  auto reader = Reader::open(name, options);
  while (!reader && monotonic_ns() < deadline) {
    std::this_thread::sleep_for(5ms);
    reader = Reader::open(name, options);
  }
  if (!reader) {
    std::printf("error=%s\n", reader.error().message.c_str());
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);
  std::vector<std::byte> buffer(reader->capacity());
  std::uint64_t received = 0, torn = 0, disorder = 0, first = 0, last = 0;
  // Borrowed, then overwritten before the check ended: the reader moved past them (not skipped)
  // but they were not delivered whole.
  std::uint64_t overwritten = 0;
  bool gone_reported = false;
  while (last < until_seq && monotonic_ns() < deadline) {
    FrameInfo info;
    ReadStatus status;
    bool whole = false;
    if (mode == "borrow") {
      status = reader->wait(50ms);
      if (status == ReadStatus::new_frame) {
        const Borrow b = reader->borrow();
        status = b.status();
        if (status == ReadStatus::new_frame) {
          info = b.info();
          whole = test::check_frame(b.bytes(), info.seq);
          if (!b.still_valid()) {  // overwritten while checked: not delivered
            ++overwritten;
            if (first == 0) first = info.seq;
            continue;
          }
        }
      }
    } else {
      status = mode == "poll" ? reader->read(buffer, info) : reader->read_next(buffer, info, 50ms);
      if (status == ReadStatus::new_frame) {
        whole = test::check_frame(std::span(buffer).first(info.size), info.seq);
      }
    }
    if (status == ReadStatus::new_frame) {
      if (gone_reported) {
        std::printf("event=resumed seq=%llu\n", static_cast<unsigned long long>(info.seq));
        std::fflush(stdout);
        gone_reported = false;
      }
      ++received;
      if (!whole) ++torn;
      if (info.seq <= last) ++disorder;
      if (first == 0) first = info.seq;
      last = info.seq;
    } else if (status == ReadStatus::writer_gone && !gone_reported) {
      gone_reported = true;
      std::printf("event=writer_gone seq=%llu\n", static_cast<unsigned long long>(last));
      std::fflush(stdout);
    }
  }
  const ReaderStats stats = reader->stats();
  std::printf("received=%llu overwritten=%llu torn=%llu disorder=%llu skipped=%llu first=%llu last=%llu "
              "overruns=%llu spins=%llu\n",
              static_cast<unsigned long long>(received), static_cast<unsigned long long>(overwritten),
              static_cast<unsigned long long>(torn),
              static_cast<unsigned long long>(disorder),
              static_cast<unsigned long long>(stats.skipped), static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(last), static_cast<unsigned long long>(stats.overruns),
              static_cast<unsigned long long>(stats.spins));
  return last >= until_seq ? 0 : 1;
}

int run_waitset(const std::string& names, std::uint64_t until_seq, long timeout_ms,
                const std::string& strategy) {
  const std::int64_t deadline = monotonic_ns() + timeout_ms * 1'000'000;
  std::vector<Reader> readers;
  for (std::size_t at = 0; at <= names.size();) {
    const std::size_t comma = std::min(names.find(',', at), names.size());
    const std::string name = names.substr(at, comma - at);
    auto reader = Reader::open(name);
    while (!reader && monotonic_ns() < deadline) {
      std::this_thread::sleep_for(5ms);
      reader = Reader::open(name);
    }
    if (!reader) {
      std::printf("error=%s\n", reader.error().message.c_str());
      return 1;
    }
    readers.push_back(std::move(*reader));
    at = comma + 1;
  }
  WaitSet set({.strategy = strategy == "round_robin" ? WaitSetStrategy::round_robin
                                                     : WaitSetStrategy::futex_waitv});
  for (Reader& r : readers) (void)set.add(r);
  std::printf("ready\n");
  std::fflush(stdout);
  std::vector<std::uint64_t> last(readers.size(), 0), received(readers.size(), 0),
      torn(readers.size(), 0);
  std::vector<std::byte> buffer;
  auto done = [&] {
    for (std::uint64_t l : last) {
      if (l < until_seq) return false;
    }
    return true;
  };
  while (!done() && monotonic_ns() < deadline) {
    const auto ready = set.wait(50ms);
    if (!ready) continue;
    Reader& r = readers[*ready];
    buffer.resize(r.capacity());
    FrameInfo info;
    if (r.read(buffer, info) != ReadStatus::new_frame) continue;
    ++received[*ready];
    if (!test::check_frame(std::span(buffer).first(info.size), info.seq) || info.seq <= last[*ready]) {
      ++torn[*ready];
    }
    last[*ready] = info.seq;
  }
  for (std::size_t i = 0; i < readers.size(); ++i) {
    std::printf("stream=%zu received=%llu torn=%llu last=%llu\n", i,
                static_cast<unsigned long long>(received[i]), static_cast<unsigned long long>(torn[i]),
                static_cast<unsigned long long>(last[i]));
  }
  std::printf("strategy=%s\n", set.strategy() == WaitSetStrategy::futex_waitv ? "futex_waitv" : "round_robin");
  return done() ? 0 : 1;
}

int run_hold(const std::string& name) {
  auto writer = Writer::create({.name = name, .capacity = 4096});
  if (!writer) {
    std::printf("error=%s\n", writer.error().message.c_str());
    return 1;
  }
  std::printf("ready pid=%d\n", getpid());
  std::fflush(stdout);
  for (;;) pause();
}

// Races Writer::create in the test: removes the stream whenever its writer is not alive, until
// told to stop.
volatile std::sig_atomic_t stop_removing = 0;
void on_stop_removing(int) { stop_removing = 1; }

int run_remove(const std::string& name) {
  struct sigaction stop {};
  stop.sa_handler = on_stop_removing;
  sigaction(SIGTERM, &stop, nullptr);
  long removed = 0;
  while (stop_removing == 0) {
    if (destroy(name)) ++removed;
  }
  std::printf("removed=%ld\n", removed);
  return 0;
}

// The page after the copy buffer's first byte is inaccessible, so read() faults inside its copy
// of the frame; the handler reports that and waits there to be killed. A kill that follows the
// report provably lands in the middle of a copy.
// An address range that may have held ASan's own memory before this mapping: its shadow says so.
void unpoison_for_asan([[maybe_unused]] std::byte* begin, [[maybe_unused]] std::size_t size) {
#if defined(__SANITIZE_ADDRESS__)
  __asan_unpoison_memory_region(begin, size);
#endif
}

int mid_copy_report_fd = -1;
void report_mid_copy(int) {
  static const char kLine[] = "mid-copy\n";
  [[maybe_unused]] const ssize_t n = ::write(mid_copy_report_fd, kLine, sizeof kLine - 1);
  for (;;) pause();
}

int run_stall_in_copy(const std::string& name) {
  auto reader = Reader::open(name);
  if (!reader) {
    std::printf("error=%s\n", reader.error().message.c_str());
    return 1;
  }
  // The buffer spans a whole frame, all of it ours, but only its first page is writable: the copy
  // runs into the guard after one page. Under AddressSanitizer the memcpy interceptor checks the
  // whole range first, so it must not reach past this mapping (ASan's own memory lies around it).
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t size = std::max(2 * page, (reader->capacity() + page - 1) / page * page);
  auto* buffer = static_cast<std::byte*>(
      mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
  if (buffer == MAP_FAILED || mprotect(buffer + page, size - page, PROT_NONE) != 0) {
    std::printf("error=cannot map the copy buffer\n");
    return 1;
  }
  unpoison_for_asan(buffer, size);
  mid_copy_report_fd = STDOUT_FILENO;
  struct sigaction on_fault {};
  on_fault.sa_handler = report_mid_copy;
  sigaction(SIGSEGV, &on_fault, nullptr);
  std::printf("ready\n");
  std::fflush(stdout);
  const std::span<std::byte> out(buffer, reader->capacity());
  for (;;) {
    FrameInfo info;
    if (reader->read_next(out, info, 50ms) == ReadStatus::buffer_too_small) return 1;
  }
}

int run_hold_borrow(const std::string& name) {
  auto reader = Reader::open(name);
  if (!reader) {
    std::printf("error=%s\n", reader.error().message.c_str());
    return 1;
  }
  for (;;) {
    if (reader->wait(50ms) != ReadStatus::new_frame) continue;
    const Borrow held = reader->borrow();
    if (held.status() != ReadStatus::new_frame) continue;
    std::printf("holding seq=%llu\n", static_cast<unsigned long long>(held.info().seq));
    std::fflush(stdout);
    for (;;) pause();
  }
}

}  // namespace

// A camera whose calibration changes while a reader in another process reads it (issue 21).
int run_recalibrate(const std::string& name) {
  SensorInfo info;
  info.frame_id = "camera_a";
  info.mounting = Mounting::from_xyz_rpy(1.0, 0.0, 1.5, 0.0, 0.0, 0.0);
  CameraCalibration c;
  c.width = 640;
  c.height = 480;
  c.k = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  info.calibration = c;
  StreamSpec spec;
  spec.name = name;
  spec.capacity = 64;
  spec.sensor = info;
  auto writer = Writer::create(spec);
  if (!writer) {
    std::printf("error=%s\n", writer.error().message.c_str());
    return 1;
  }
  const std::byte frame[8] = {};
  if (writer->write(frame, sizeof frame, realtime_ns()) != WriteStatus::ok) return 1;
  std::printf("ready\n");
  std::fflush(stdout);
  // The reader has read frame 1 (and its description) once it sleeps for the next frame.
  const std::int64_t deadline = monotonic_ns() + 30'000'000'000;
  for (;;) {
    auto status = inspect(name);
    if (status && status->sleeping_readers > 0) break;
    if (monotonic_ns() > deadline) return 1;
    std::this_thread::sleep_for(1ms);
  }
  info.frame_id = "camera_b";
  info.calibration->k[0] = 510;
  if (auto set = writer->set_sensor_info(info); !set) {
    std::printf("error=%s\n", set.error().message.c_str());
    return 1;
  }
  if (writer->write(frame, sizeof frame, realtime_ns()) != WriteStatus::ok) return 1;
  std::printf("done\n");
  std::fflush(stdout);
  return 0;
}

// Opens each stream the moment its name appears (spinning on open) and asks at once for its
// writer and description: a new stream must have both from the start.
int run_open_at_once(const std::string& prefix, unsigned count) {
  std::printf("ready\n");
  std::fflush(stdout);
  unsigned without_description = 0;
  unsigned without_writer = 0;
  const std::int64_t deadline = monotonic_ns() + 120'000'000'000;  // never hang a test run
  for (unsigned i = 0; i < count; ++i) {
    const std::string name = prefix + "_" + std::to_string(i);
    Expected<Reader> reader = Reader::open(name);
    while (!reader) {
      if (monotonic_ns() > deadline) {
        std::printf("error=%s never appeared\n", name.c_str());
        return 1;
      }
      reader = Reader::open(name);
    }
    auto described = reader->sensor_info();
    if (!described || !described->has_value()) ++without_description;
    if (auto status = inspect(name); status && status->writer_pid == 0) ++without_writer;
  }
  std::printf("without_description=%u without_writer=%u\n", without_description, without_writer);
  std::fflush(stdout);
  return without_description == 0 && without_writer == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 7 && args[0] == "writer") {
    return run_writer(args[1], std::stoull(args[2]), std::stod(args[3]), std::stoul(args[4]),
                      std::stoul(args[5]), std::stol(args[6]));
  }
  if (args.size() == 5 && args[0] == "reader") {
    return run_reader(args[1], std::stoull(args[2]), std::stol(args[3]), args[4]);
  }
  if (args.size() == 5 && args[0] == "waitset") {
    return run_waitset(args[1], std::stoull(args[2]), std::stol(args[3]), args[4]);
  }
  if (args.size() == 2 && args[0] == "hold") return run_hold(args[1]);
  if (args.size() == 2 && args[0] == "remove") return run_remove(args[1]);
  if (args.size() == 2 && args[0] == "stall-in-copy") return run_stall_in_copy(args[1]);
  if (args.size() == 2 && args[0] == "hold-borrow") return run_hold_borrow(args[1]);
  if (args.size() == 2 && args[0] == "recalibrate") return run_recalibrate(args[1]);
  if (args.size() == 3 && args[0] == "open-at-once") return run_open_at_once(args[1], static_cast<unsigned>(std::stoul(args[2])));
  std::fprintf(stderr, "usage: see the comment at the top of tests/sim/peer.cpp\n");
  return 2;
}
