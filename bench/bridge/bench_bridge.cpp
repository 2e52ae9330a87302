// SPDX-License-Identifier: Apache-2.0
// bench_bridge: SIM → sim_dds_bridge → Cyclone DDS subscriber, against a plain Fast DDS
// publisher that sends the same ROS 2 message from memory, in the same run, for the SIM paper's
// four payloads at their sensor rates. Per case and path: messages received of those sent,
// latency (frame stamp → Cyclone take, mean and p99), throughput, and the CPU time of the
// publishing process (the bridge, or the plain publisher) per second of the same window: from
// just before the first frame to a fixed time after the last, counted in nanoseconds by the
// scheduler (/proc/PID/task/*/schedstat), since a clock tick (10 ms) is more than either path
// spends in a second at LiDAR rates. With --runs N the cases repeat N times (the two paths in
// alternating order) and a summary gives the bridge/plain CPU ratio per case with its 95 %
// interval, and the machine's load during the runs.
//
//   bench_bridge [--seconds 5] [--runs 5] [--reliable] [--case camera_1920x1200_30Hz]
//
// Run it as root so it can use a private network namespace (loopback only); otherwise it runs on
// the machine's interfaces. Speed is reported, never asserted.
#include <dirent.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cyclone.hpp"
#include "dds_session.hpp"
#include "ros_message_type.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/clock.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/writer.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"

namespace {

using namespace std::chrono_literals;
using sim::testing::CycloneParticipant;
using sim::testing::CycloneReader;

struct Case {
  std::string name;
  sim::Layout layout;
  double rate_hz;
};

// The SIM paper's streams (Table I): indoor and outdoor LiDAR as PointXYZ arrays, two cameras.
std::vector<Case> paper_cases() {
  return {
      {"lidar_2160pts_20Hz", sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 2160)), 20},
      {"lidar_115200pts_10Hz", sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 115200)), 10},
      {"camera_640x480_30Hz", sim::Layout::of(sim::ImageLayout::packed(640, 480, sim::PixelFormat::bgr8)), 30},
      {"camera_1920x1200_30Hz", sim::Layout::of(sim::ImageLayout::packed(1920, 1200, sim::PixelFormat::bgr8)), 30},
  };
}

// CPU time of every thread of a process, in seconds: the scheduler's nanosecond accounting of
// each live thread (/proc/PID/task/TID/schedstat, first field). Fast DDS and the bridge keep
// their threads for the whole run, so no thread's time is lost between two samples.
double cpu_seconds(pid_t pid) {
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  DIR* dir = opendir(tasks.c_str());
  if (dir == nullptr) return 0;
  double total_ns = 0;
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    std::ifstream in(tasks + "/" + entry->d_name + "/schedstat");
    double ns = 0;
    if (in >> ns) total_ns += ns;
  }
  closedir(dir);
  return total_ns / 1e9;
}

// The whole machine's busy and total CPU time so far (/proc/stat), in clock ticks.
std::pair<double, double> machine_cpu() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  in >> cpu;
  double busy = 0, total = 0, value = 0;
  for (int field = 0; field < 8 && (in >> value); ++field) {
    total += value;
    if (field != 3 && field != 4) busy += value;  // idle and iowait are not busy
  }
  return {busy, total};
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

struct Result {
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  double mean_ms = 0;
  double p99_ms = 0;
  double mb_per_s = 0;
  double cpu_percent = 0;
};

// Counts what a Cyclone subscriber takes of `dds_topic`, and each message's latency.
template <typename Sample>
class Receiver {
 public:
  Receiver(const CycloneParticipant& p, const dds_topic_descriptor_t* type, const std::string& topic,
           bool reliable)
      : reader_(p, type, topic, reliable), thread_([this] { run(); }) {}
  ~Receiver() {
    stop_ = true;
    thread_.join();
  }
  std::vector<double> latencies_ms() const { return latencies_; }
  std::uint64_t bytes() const { return bytes_; }

 private:
  void run() {
    while (!stop_) {
      reader_.take(
          [this](const Sample& s) {
            const std::int64_t stamp = std::int64_t{s.header.stamp.sec} * 1'000'000'000 + s.header.stamp.nanosec;
            latencies_.push_back(static_cast<double>(sim::realtime_ns() - stamp) / 1e6);
            bytes_ += s.data._length;
          },
          100ms);
    }
  }
  CycloneReader<Sample> reader_;
  std::atomic<bool> stop_{false};
  std::vector<double> latencies_;
  std::uint64_t bytes_ = 0;
  std::thread thread_;
};

Result summarize(std::vector<double> latencies, std::uint64_t bytes, std::uint64_t sent,
                 double seconds, double cpu, double cpu_window) {
  Result r;
  r.sent = sent;
  r.received = latencies.size();
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    double sum = 0;
    for (double l : latencies) sum += l;
    r.mean_ms = sum / static_cast<double>(latencies.size());
    r.p99_ms = latencies[std::min(latencies.size() - 1, latencies.size() * 99 / 100)];
  }
  r.mb_per_s = static_cast<double>(bytes) / 1e6 / seconds;
  r.cpu_percent = 100.0 * cpu / cpu_window;
  return r;
}

// Frames with a recognizable pattern, paced at the case's rate, stamped with the present.
void pace(const Case& c, double seconds, const std::function<void(std::int64_t)>& send) {
  // One sleep per frame, so the plain publisher's CPU is its sending, not its pacing. The first
  // frame goes a period after the start, so a CPU window opened at the start holds it.
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / c.rate_hz));
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9));
  for (auto next = start + period; next <= end; next += period) {
    std::this_thread::sleep_until(next);
    send(sim::realtime_ns());
  }
}

// How long after the last frame the CPU window of either path ends: the last messages leave.
constexpr auto kTail = std::chrono::milliseconds(300);

// CPU seconds of `pid` and the wall-clock seconds between start() and stop().
class CpuWindow {
 public:
  explicit CpuWindow(pid_t pid) : pid_(pid) {}
  void start() {
    cpu0_ = cpu_seconds(pid_);
    wall0_ = std::chrono::steady_clock::now();
  }
  void stop() {
    cpu_ = cpu_seconds(pid_) - cpu0_;
    wall_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  }
  double cpu() const { return cpu_; }
  double wall() const { return wall_; }

 private:
  pid_t pid_;
  double cpu0_ = 0, cpu_ = 0, wall_ = 0;
  std::chrono::steady_clock::time_point wall0_;
};

template <typename Sample>
Result run_case(const Case& c, const dds_topic_descriptor_t* type, const std::string& self,
                const std::string& bridge_tool, bool via_bridge, double seconds, bool reliable) {
  static int counter = 0;
  const std::string name = "/bench_bridge_" + std::to_string(::getpid()) + "_" +
                           std::to_string(counter++) + (via_bridge ? "_b" : "_p");
  // The bridge publishes an image stream on <stream>/image_raw and points on <stream>
  // (docs/bridge.md, "Topics"); the plain publisher publishes on the stream's own name.
  const bool image_raw = via_bridge && c.layout.kind == sim::LayoutKind::image;
  CycloneParticipant participant;
  Receiver<Sample> receiver(participant, type, "rt" + name + (image_raw ? "/image_raw" : ""), reliable);
  std::uint64_t sent = 0;
  double cpu = 0, window = 1;
  if (via_bridge) {
    sim::StreamSpec spec;
    spec.name = name;
    spec.layout = c.layout;
    auto writer = sim::Writer::create(spec);
    if (!writer) throw std::runtime_error(writer.error().message);
    std::vector<std::string> argv = {bridge_tool, "--publish", name, "--quiet"};
    if (reliable) argv.push_back("--reliable");
    sim::testing::Process bridge(argv);
    std::this_thread::sleep_for(2s);  // discovery and matching
    CpuWindow measured(bridge.pid());
    measured.start();
    pace(c, seconds, [&](std::int64_t stamp) {
      // The producer's cost is not the bridge's: only the first byte changes per frame.
      sim::Loan loan = writer->loan();
      loan.bytes()[0] = static_cast<std::byte>(sent & 0xff);
      if (std::move(loan).commit(c.layout.min_capacity(), stamp) == sim::WriteStatus::ok) ++sent;
    });
    std::this_thread::sleep_for(kTail);
    measured.stop();
    cpu = measured.cpu();
    window = measured.wall();
    bridge.signal(SIGTERM);
    bridge.wait();
    (void)sim::destroy(name, true);
  } else {
    std::vector<std::string> argv = {self, "--plain-publisher", name, "--case", c.name,
                                     "--seconds", std::to_string(seconds)};
    if (reliable) argv.push_back("--reliable");
    sim::testing::Process publisher(argv);
    // The publisher says "started" and sends its first frame a period later (pace()); the
    // window opens when the line is read, well within that period.
    const auto started = publisher.wait_for_line("started");
    CpuWindow measured(publisher.pid());
    measured.start();
    const auto done = publisher.wait_for_line("sent", std::chrono::milliseconds(static_cast<int>(seconds * 1000) + 30'000));
    std::this_thread::sleep_for(kTail);
    measured.stop();
    cpu = measured.cpu();
    window = measured.wall();
    if (done) sent = std::stoull(done->substr(done->find(' ') + 1));
    publisher.signal(SIGTERM);
    publisher.wait();
    (void)started;
  }
  return summarize(receiver.latencies_ms(), receiver.bytes(), sent, seconds, cpu, window);
}

// The reference: the same message serialized from process memory by the same Fast DDS type
// (one copy), no SIM in between.
int plain_publisher(const std::string& name, const Case& c, double seconds, bool reliable) {
  auto session = sim::bridge::DdsSession::create(0);
  if (!session) return 1;
  auto type = sim::ros2::message_type_for(c.layout);
  std::string error;
  sim::bridge::QosChoice qos;
  qos.reliable = reliable;
  auto* writer = (*session)->create_writer(sim::ros2::dds_topic_name(name), *type, qos, error);
  if (writer == nullptr) return 1;
  std::vector<std::byte> frame(c.layout.min_capacity());
  std::this_thread::sleep_for(2s);
  std::printf("started\n");
  std::fflush(stdout);
  std::uint64_t sent = 0;
  pace(c, seconds, [&](std::int64_t stamp) {
    frame[0] = static_cast<std::byte>(sent & 0xff);  // sent from memory as it is, like a ready frame
    sim::FrameInfo info;
    info.stamp_ns = stamp;
    info.size = frame.size();
    info.layout = c.layout;
    auto plan = sim::ros2::plan_frame(info, name.substr(1));
    sim::bridge::OutgoingMessage message{&plan.value(), frame, nullptr};
    writer->write(&message);
    ++sent;
  });
  std::printf("sent %llu\n", static_cast<unsigned long long>(sent));
  std::fflush(stdout);
  std::this_thread::sleep_for(60s);  // until the bench ends it
  (*session)->delete_writer(writer);
  return 0;
}

// Two-sided 95 % quantile of Student's t for `dof` degrees of freedom.
double t95(std::size_t dof) {
  static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262,
                                 2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101,
                                 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052,
                                 2.048, 2.045, 2.042};
  return dof == 0 ? NAN : dof <= 30 ? table[dof - 1] : 1.96;
}

// "mean [low, high]" of the samples, the interval being the mean's 95 % confidence interval.
std::string mean_interval(const std::vector<double>& v, int digits) {
  double mean = 0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  char text[96];
  if (v.size() < 2) {
    std::snprintf(text, sizeof text, "%.*f", digits, mean);
    return text;
  }
  double squares = 0;
  for (double x : v) squares += (x - mean) * (x - mean);
  const double sd = std::sqrt(squares / static_cast<double>(v.size() - 1));
  const double half = t95(v.size() - 1) * sd / std::sqrt(static_cast<double>(v.size()));
  std::snprintf(text, sizeof text, "%.*f [%.*f, %.*f]", digits, mean, digits, mean - half, digits,
                mean + half);
  return text;
}

struct Settings {
  double seconds = 5;
  int runs = 1;
  bool reliable = false;
  std::string only;        // --case: run only this case
  std::string plain_name;  // --plain-publisher: this process is the plain publisher
};

// The file of this program, so it can start itself as the plain publisher.
std::string self_path() {
  char path[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
  return n > 0 ? std::string(path, static_cast<std::size_t>(n)) : "/proc/self/exe";
}

// One case over one path, printed as a row of the table.
Result run_path(const Case& c, const std::string& me, bool via_bridge, int run, const Settings& s) {
  const Result r = c.layout.kind == sim::LayoutKind::points
                       ? run_case<sensor_msgs_msg_dds__PointCloud2_>(
                             c, &sensor_msgs_msg_dds__PointCloud2__desc, me, SIM_DDS_BRIDGE,
                             via_bridge, s.seconds, s.reliable)
                       : run_case<sensor_msgs_msg_dds__Image_>(
                             c, &sensor_msgs_msg_dds__Image__desc, me, SIM_DDS_BRIDGE,
                             via_bridge, s.seconds, s.reliable);
  std::printf("| %d | %s | %s | %s | %llu/%llu | %.2f | %.2f | %.1f | %.2f |\n", run,
              c.name.c_str(), via_bridge ? "SIM → bridge" : "plain Fast DDS",
              s.reliable ? "reliable" : "best effort",
              static_cast<unsigned long long>(r.received), static_cast<unsigned long long>(r.sent),
              r.mean_ms, r.p99_ms, r.mb_per_s, r.cpu_percent);
  std::fflush(stdout);
  return r;
}

// What the runs of one case gave, for the summary.
struct Samples {
  std::vector<double> plain, bridge, ratio, difference;
  std::uint64_t plain_received = 0, bridge_received = 0, sent = 0;

  void add(const Result& plain_result, const Result& bridge_result) {
    plain.push_back(plain_result.cpu_percent);
    bridge.push_back(bridge_result.cpu_percent);
    ratio.push_back(bridge_result.cpu_percent / plain_result.cpu_percent);
    difference.push_back(bridge_result.cpu_percent - plain_result.cpu_percent);
    plain_received += plain_result.received;
    bridge_received += bridge_result.received;
    sent += bridge_result.sent;
  }
};

// Every run of every case over both paths, a table row each; the samples by case.
std::map<std::string, Samples> run_all(const Settings& s, const std::string& me) {
  std::printf("| run | case | path | QoS | received/sent | mean ms | p99 ms | MB/s | publisher CPU %% |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  std::map<std::string, Samples> samples;
  for (int run = 1; run <= s.runs; ++run) {
    for (const Case& c : paper_cases()) {
      if (!s.only.empty() && c.name != s.only) continue;
      Result results[2];  // plain, bridge
      // Alternating which path goes first cancels a trend in the machine's load.
      const bool bridge_first = run % 2 == 0;
      for (bool via_bridge : {bridge_first, !bridge_first}) {
        results[via_bridge ? 1 : 0] = run_path(c, me, via_bridge, run, s);
      }
      samples[c.name].add(results[0], results[1]);
    }
  }
  return samples;
}

void print_summary(const std::map<std::string, Samples>& samples, const Settings& settings) {
  std::printf("\nCPU of the publishing process, %% of one core, mean [95 %% interval] over %d run%s "
              "of %.0f s per case and path:\n\n",
              settings.runs, settings.runs == 1 ? "" : "s", settings.seconds);
  std::printf("| case | plain Fast DDS | SIM → bridge | bridge / plain | bridge − plain | received plain / bridge / sent |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (const Case& c : paper_cases()) {
    const auto it = samples.find(c.name);
    if (it == samples.end()) continue;
    const Samples& s = it->second;
    std::printf("| %s | %s | %s | %s | %s | %llu / %llu / %llu |\n", c.name.c_str(),
                mean_interval(s.plain, 2).c_str(), mean_interval(s.bridge, 2).c_str(),
                mean_interval(s.ratio, 2).c_str(), mean_interval(s.difference, 2).c_str(),
                static_cast<unsigned long long>(s.plain_received),
                static_cast<unsigned long long>(s.bridge_received),
                static_cast<unsigned long long>(s.sent));
  }
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "bench_bridge",
      "SIM → sim_dds_bridge → Cyclone DDS against a plain Fast DDS publisher, same run.");
  Settings settings;
  cli.add_option("--seconds", settings.seconds, "seconds per case and path").positive();
  cli.add_option("--runs", settings.runs, "repeat every case this many times; with 2 or more, a summary "
                                          "gives the bridge/plain CPU ratio with its 95 % interval")
      .in_range(1, 100);
  cli.add_flag("--reliable", settings.reliable, "reliable QoS instead of best effort");
  std::vector<std::string> case_names;
  for (const Case& c : paper_cases()) case_names.push_back(c.name);
  cli.add_option("--case", settings.only, "run only this case").one_of(std::move(case_names));
  // The copy of itself bench_bridge starts as the plain publisher; not in --help.
  cli.add_option("--plain-publisher", settings.plain_name, "be the plain publisher of this topic")
      .hidden();
  if (const auto code = cli.parse(argc, argv)) return *code;

  if (!settings.plain_name.empty()) {
    for (const Case& c : paper_cases()) {
      if (c.name == settings.only) {
        return plain_publisher(settings.plain_name, c, settings.seconds, settings.reliable);
      }
    }
    return 2;
  }
  if (auto why = sim::testing::enter_private_network(sim::testing::Multicast::on)) {
    std::fprintf(stderr, "bench_bridge: %s: running on this machine's interfaces\n", why->c_str());
  }
  const std::string load_before = load_average();
  const auto machine_before = machine_cpu();
  const auto samples = run_all(settings, self_path());
  const auto machine_after = machine_cpu();
  const double busy = 100.0 * (machine_after.first - machine_before.first) /
                      (machine_after.second - machine_before.second);
  print_summary(samples, settings);
  std::printf("\nMachine: %ld cores, busy %.0f %% of them during the runs (this bench included); "
              "load average %s before, %s after.\n",
              sysconf(_SC_NPROCESSORS_ONLN), busy, load_before.c_str(), load_average().c_str());
  return 0;
}
