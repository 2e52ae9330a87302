// SPDX-License-Identifier: Apache-2.0
// The Hesai path as a consumer sees it, on the real Pandar64 capture (issue 3's speed section):
//
//  1. Cut to visible: how long from the arrival of the packet that completes a revolution until
//     the frame is published (LidarStream::push of that packet: decode, cut, commit), and until
//     a reader blocked in wait() on another thread is running with it. Beside it, for scale,
//     the cost of an ordinary packet's push.
//  2. The live driver: sim_lidar_hesai as its own process, fed the capture's payloads over UDP
//     on 127.0.0.1 at the sensor's recorded rate (looped): its user+system CPU time over the
//     run as a percentage of one core (the target: under 5 %), how often it woke, and
//     the time from sending a revolution's completing packet until a reader blocked in wait()
//     in this process runs with the frame (UDP, the driver's naps and decode, the futex wake).
//
//   bench_hesai_live [--seconds S] [--revolutions N]
//
// Timings are printed, never asserted (tests must not depend on the machine's speed).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hesai_test_data.hpp"
#include "sim/hesai/frame_assembler.hpp"
#include "sim/hesai/lidar_stream.hpp"
#include "sim/sim.hpp"

extern char** environ;

namespace {

using Payloads = std::vector<hesai_test::UdpPayload>;

struct Percentiles {
  double p50_us, p99_us, max_us;
};

Percentiles summarise(std::vector<std::int64_t> ns) {
  std::sort(ns.begin(), ns.end());
  const auto at = [&](double q) {
    return static_cast<double>(ns[std::min(ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ns.size())))]) / 1e3;
  };
  return {at(0.50), at(0.99), static_cast<double>(ns.back()) / 1e3};
}

std::string unique_stream(const char* what) {
  return "/bench_hesai_" + std::string(what) + "_" + std::to_string(getpid());
}

// ---- 1. cut to visible ------------------------------------------------------------------------

int measure_cut_to_visible(const Payloads& payloads, const std::string& calibration, int revolutions) {
  sim::hesai::LidarStreamConfig config;
  config.stream = unique_stream("cut");
  config.calibration = calibration;
  config.assembler.model = sim::hesai::Model::pandar64;
  auto stream = sim::hesai::LidarStream::create(config);
  if (!stream) {
    std::fprintf(stderr, "bench_hesai_live: %s\n", stream.error().message.c_str());
    return 1;
  }
  auto reader = sim::Reader::open(config.stream);
  if (!reader) {
    std::fprintf(stderr, "bench_hesai_live: %s\n", reader.error().message.c_str());
    (void)sim::destroy(config.stream, true);
    return 1;
  }

  std::atomic<std::int64_t> woken_at{0};
  std::atomic<bool> stop{false};
  std::thread consumer([&] {
    std::vector<std::byte> frame(reader->capacity());
    while (!stop.load()) {
      if (reader->wait(std::chrono::milliseconds(50)) == sim::ReadStatus::new_frame) {
        woken_at.store(sim::monotonic_ns());  // the wake-up is what is timed, not the copy
        sim::FrameInfo info;
        (void)reader->read(frame, info);  // only the wake-up is measured; the copy just drains
        while (woken_at.load() != 0 && !stop.load()) std::this_thread::yield();
      }
    }
  });

  std::vector<std::int64_t> cut_push, to_reader, ordinary_push;
  std::size_t next = 0;
  while (static_cast<int>(cut_push.size()) < revolutions) {
    const auto& payload = payloads[next];
    next = (next + 1) % payloads.size();
    if (next == 0) stream->reset();  // the capture loops
    const std::int64_t start = sim::monotonic_ns();
    const auto result = stream->push(payload.bytes, sim::realtime_ns());
    const std::int64_t visible = sim::monotonic_ns();
    if (!result.frame) {
      ordinary_push.push_back(visible - start);
      continue;
    }
    cut_push.push_back(visible - start);
    while (woken_at.load() == 0) std::this_thread::yield();
    to_reader.push_back(woken_at.load() - start);
    woken_at.store(0);
  }
  stop.store(true);
  consumer.join();
  (void)sim::destroy(config.stream, true);

  const Percentiles cut = summarise(cut_push), woken = summarise(to_reader),
                    ordinary = summarise(ordinary_push);
  std::printf("cut to visible, Pandar64 dual, %d revolutions (µs: p50 / p99 / max)\n", revolutions);
  std::printf("  completing packet pushed → frame published     %8.1f / %8.1f / %8.1f\n",
              cut.p50_us, cut.p99_us, cut.max_us);
  std::printf("  completing packet pushed → blocked reader runs %8.1f / %8.1f / %8.1f\n",
              woken.p50_us, woken.p99_us, woken.max_us);
  std::printf("  for scale: any other packet's push             %8.1f / %8.1f / %8.1f\n",
              ordinary.p50_us, ordinary.p99_us, ordinary.max_us);
  return 0;
}

// ---- 2. live driver CPU -----------------------------------------------------------------------

struct Child {
  pid_t pid = -1;
  int out = -1;  // its stdout
};

Child spawn_driver(const std::vector<std::string>& args) {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return {};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  Child child;
  if (posix_spawn(&child.pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) child.pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  child.out = pipe_fds[0];
  return child;
}

// The port from "sim_lidar_hesai: listening on 127.0.0.1:PORT", or -1.
int read_port(int fd) {
  std::string text;
  char c;
  while (read(fd, &c, 1) == 1) {
    if (c != '\n') {
      text += c;
      continue;
    }
    if (const auto at = text.find("listening on "); at != std::string::npos) {
      return std::stoi(text.substr(text.rfind(':') + 1));
    }
    text.clear();
  }
  return -1;
}

// utime + stime of a process, in seconds (/proc/PID/stat fields 14 and 15).
double cpu_seconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  std::istringstream fields(line.substr(line.rfind(')') + 2));
  std::string skip;
  for (int i = 3; i < 14; ++i) fields >> skip;
  double utime = 0, stime = 0;
  fields >> utime >> stime;
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Times the process's main thread (the driver's receive loop) went to sleep and was woken:
// voluntary context switches, from /proc/PID/status. Unlike CPU time, not inflated by a busy machine.
std::uint64_t wake_ups(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("voluntary_ctxt_switches:", 0) == 0) return std::stoull(line.substr(line.find(':') + 1));
  }
  return 0;
}

// An assembler beside the driver, decoding the same packets in step: it tells which packet
// completes each revolution, and the stamp of the frame it completes.
sim::Expected<sim::hesai::FrameAssembler> twin_assembler(const std::string& calibration) {
  auto table = sim::hesai::Calibration::load(calibration, sim::hesai::Model::pandar64);
  if (!table) return table.error();
  return sim::hesai::FrameAssembler::create(std::move(*table), {});
}

// sim_lidar_hesai on an ephemeral loopback port, publishing `stream`; port -1 if it did not
// start (then nothing is left running).
struct Driver {
  Child process;
  int port = -1;
};
Driver start_driver(const std::string& stream, const std::string& calibration) {
  Driver driver;
  driver.process = spawn_driver({SIM_LIDAR_HESAI, "--model", "Pandar64", "--bind", "127.0.0.1",
                                 "--port", "0", "--stream", stream, "--calibration", calibration,
                                 "--status-interval", "0"});
  driver.port = driver.process.pid > 0 ? read_port(driver.process.out) : -1;
  if (driver.port > 0) return driver;
  if (driver.process.pid > 0) {
    kill(driver.process.pid, SIGKILL);
    waitpid(driver.process.pid, nullptr, 0);
  }
  if (driver.process.out >= 0) close(driver.process.out);
  return driver;
}

void stop_driver(const Driver& driver) {
  kill(driver.process.pid, SIGTERM);
  waitpid(driver.process.pid, nullptr, 0);
  close(driver.process.out);
}

// One frame seen from one side: its sensor stamp (which pairs the sides) and a monotonic time
// (when its completing packet was sent, or when it woke the reader).
struct Event {
  std::int64_t stamp_ns;
  std::int64_t at_ns;
};

// A reader blocked in wait() on its own thread, noting when each frame woke it.
class WakeRecorder {
 public:
  explicit WakeRecorder(const std::string& stream) : thread_([this, stream] { run(stream); }) {}
  ~WakeRecorder() {
    if (thread_.joinable()) finish();
  }
  WakeRecorder(const WakeRecorder&) = delete;
  WakeRecorder& operator=(const WakeRecorder&) = delete;
  // Stops the thread and hands over what it saw.
  std::vector<Event> finish() {
    stop_.store(true);
    thread_.join();
    return std::move(woken_);
  }

 private:
  void run(const std::string& stream) {
    // The driver creates the stream just after it reports its port.
    auto reader = sim::Reader::open(stream);
    for (int attempt = 0; !reader && attempt < 200 && !stop_.load(); ++attempt) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      reader = sim::Reader::open(stream);
    }
    if (!reader) return;
    std::vector<std::byte> frame(reader->capacity());
    while (!stop_.load()) {
      if (reader->wait(std::chrono::milliseconds(50)) != sim::ReadStatus::new_frame) continue;
      const std::int64_t now = sim::monotonic_ns();
      sim::FrameInfo info;
      if (reader->read(frame, info) == sim::ReadStatus::new_frame) woken_.push_back({info.stamp_ns, now});
    }
  }

  std::atomic<bool> stop_{false};
  std::vector<Event> woken_;
  std::thread thread_;  // last: it starts once the members it uses exist
};

struct SendLog {
  std::uint64_t sent = 0;
  std::vector<Event> cuts_sent;  // the packets that complete a revolution
};

// Sends the payloads to the driver for `seconds`, paced on an absolute schedule from the
// capture's own timestamps and looped; the twin decodes each packet as it goes.
SendLog send_at_recorded_rate(const Payloads& payloads, int port, double seconds,
                              sim::hesai::FrameAssembler& twin,
                              std::vector<sim::LidarPoint>& twin_points) {
  const int sock = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const std::int64_t capture_span = payloads.back().capture_ns - payloads.front().capture_ns +
                                    (payloads.back().capture_ns - payloads.front().capture_ns) /
                                        static_cast<std::int64_t>(payloads.size() - 1);
  SendLog log;
  const std::int64_t start = sim::monotonic_ns();
  const auto end = start + static_cast<std::int64_t>(seconds * 1e9);
  for (std::int64_t loop_start = start; loop_start < end; loop_start += capture_span) {
    for (const auto& p : payloads) {
      const std::int64_t due = loop_start + (p.capture_ns - payloads.front().capture_ns);
      if (due >= end) break;
      timespec at{static_cast<time_t>(due / 1'000'000'000), static_cast<long>(due % 1'000'000'000)};
      const auto completes = twin.push(p.bytes, 0).frame;
      if (completes) twin.set_output(twin_points);
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr);
      const std::int64_t send_ns = sim::monotonic_ns();
      sendto(sock, p.bytes.data(), p.bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
      if (completes) log.cuts_sent.push_back({completes->stamp_ns, send_ns});
      ++log.sent;
    }
  }
  close(sock);
  return log;
}

// From sending each revolution's completing packet to the reader running with that frame.
std::vector<std::int64_t> send_to_reader_ns(const std::vector<Event>& woken,
                                            const std::vector<Event>& cuts_sent) {
  std::vector<std::int64_t> latencies;
  std::size_t next_cut = 0;
  for (const Event& w : woken) {
    while (next_cut < cuts_sent.size() && cuts_sent[next_cut].stamp_ns != w.stamp_ns) ++next_cut;
    if (next_cut == cuts_sent.size()) break;
    latencies.push_back(w.at_ns - cuts_sent[next_cut++].at_ns);
  }
  return latencies;
}

struct DriverRun {
  double wall_s = 0;
  double cpu_s = 0;  // the driver's user + system time
  std::uint64_t sent = 0;
  std::uint64_t wakes = 0;
  std::uint64_t frames = 0;
  std::vector<std::int64_t> send_to_reader_ns;
};

int report(const DriverRun& run) {
  std::printf("live driver CPU, Pandar64 dual at the recorded rate over UDP on 127.0.0.1\n");
  std::printf("  %.1f s, %llu packets (%.0f/s), %llu frames published\n", run.wall_s,
              static_cast<unsigned long long>(run.sent), static_cast<double>(run.sent) / run.wall_s,
              static_cast<unsigned long long>(run.frames));
  std::printf("  sim_lidar_hesai used %.3f s of CPU = %.2f %% of one core (target < 5 %%)\n",
              run.cpu_s, 100.0 * run.cpu_s / run.wall_s);
  std::printf("  it woke %.0f times a second (%.1f packets per wake-up)\n",
              static_cast<double>(run.wakes) / run.wall_s,
              run.wakes == 0 ? 0.0 : static_cast<double>(run.sent) / static_cast<double>(run.wakes));
  if (run.send_to_reader_ns.empty()) {
    std::printf("  no frame reached the reader: the send-to-reader time cannot be measured\n");
    return 1;
  }
  const Percentiles latency = summarise(run.send_to_reader_ns);
  std::printf("  completing packet sent → blocked reader runs (%zu revolutions, µs: p50 / p99 / max)\n"
              "                                                 %8.1f / %8.1f / %8.1f\n",
              run.send_to_reader_ns.size(), latency.p50_us, latency.p99_us, latency.max_us);
  return 0;
}

int measure_driver_cpu(const Payloads& payloads, const std::string& calibration, double seconds) {
  auto twin = twin_assembler(calibration);
  if (!twin) {
    std::fprintf(stderr, "bench_hesai_live: %s\n", twin.error().message.c_str());
    return 1;
  }
  std::vector<sim::LidarPoint> twin_points(sim::hesai::frame_capacity(sim::hesai::Model::pandar64, 2));
  twin->set_output(twin_points);
  const std::string stream = unique_stream("live");
  const Driver driver = start_driver(stream, calibration);
  if (driver.port <= 0) {
    std::fprintf(stderr, "bench_hesai_live: %s did not start\n", SIM_LIDAR_HESAI);
    return 1;
  }

  WakeRecorder reader(stream);
  const pid_t pid = driver.process.pid;
  const double cpu_before = cpu_seconds(pid);
  const std::uint64_t wake_ups_before = wake_ups(pid);
  const std::int64_t start = sim::monotonic_ns();
  SendLog log = send_at_recorded_rate(payloads, driver.port, seconds, *twin, twin_points);
  DriverRun run;
  run.wall_s = static_cast<double>(sim::monotonic_ns() - start) / 1e9;
  run.cpu_s = cpu_seconds(pid) - cpu_before;
  run.wakes = wake_ups(pid) - wake_ups_before;
  run.sent = log.sent;
  if (auto status = sim::inspect(stream)) run.frames = status->frames_published;
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the last frame's wake-up
  run.send_to_reader_ns = send_to_reader_ns(reader.finish(), log.cuts_sent);
  stop_driver(driver);
  (void)sim::destroy(stream, true);
  return report(run);
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  int revolutions = 200;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::printf(
          "Usage: bench_hesai_live [--seconds S] [--revolutions N]\n"
          "Times a revolution from its last packet to a reader (N revolutions, default 200), then\n"
          "feeds sim_lidar_hesai the Pandar64 capture over UDP at its recorded rate for S seconds\n"
          "(default 10) and reports the driver's CPU use, its wake-ups, and the time from sending\n"
          "a revolution's last packet to a blocked reader in this process.\n");
      return 0;
    }
    if (i + 1 < argc && arg == "--seconds") {
      seconds = std::atof(argv[++i]);
    } else if (i + 1 < argc && arg == "--revolutions") {
      revolutions = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "bench_hesai_live: unknown option '%s'; see --help\n", arg.c_str());
      return 2;
    }
  }
  if (seconds <= 0 || revolutions <= 0) {
    std::fprintf(stderr, "bench_hesai_live: --seconds and --revolutions must be positive\n");
    return 2;
  }
  const Payloads payloads = hesai_test::read_udp_payloads(hesai_test::data_path("pandar64_dual.pcap"));
  const std::string calibration = hesai_test::data_path("pandar64.calibration.csv").string();
  if (const int rc = measure_cut_to_visible(payloads, calibration, revolutions)) return rc;
  return measure_driver_cpu(payloads, calibration, seconds);
}
