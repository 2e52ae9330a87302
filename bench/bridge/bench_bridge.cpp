// SPDX-License-Identifier: Apache-2.0
// bench_bridge: SIM → sim_dds_bridge → Cyclone DDS subscriber, against a plain Fast DDS
// publisher that sends the same ROS 2 message from memory, in the same run, for the SIM paper's
// four payloads at their sensor rates. Per case and path: messages received of those sent,
// latency (frame stamp → Cyclone take, mean and p99), throughput, and the CPU time of the
// publishing process (the bridge, or the plain publisher) per second.
//
//   bench_bridge [--seconds 5] [--reliable] [--case camera_1920x1200]
//
// Run it as root so it can use a private network namespace (loopback only); otherwise it runs on
// the machine's interfaces. Speed is reported, never asserted.
#include <net/if.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cyclone.hpp"
#include "dds_session.hpp"
#include "ros_message_type.hpp"
#include "sim/clock.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/writer.hpp"
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

// utime + stime of a process, in seconds.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = stat.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(stat.substr(close + 2));
  std::string skip;
  for (int i = 0; i < 11; ++i) fields >> skip;  // state … cmajflt
  double utime = 0, stime = 0;
  fields >> utime >> stime;
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
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
                 double seconds, double cpu) {
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
  r.cpu_percent = 100.0 * cpu / seconds;
  return r;
}

// Frames with a recognizable pattern, paced at the case's rate, stamped with the present.
void pace(const Case& c, double seconds, const std::function<void(std::int64_t)>& send) {
  // One sleep per frame, so the plain publisher's CPU is its sending, not its pacing.
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / c.rate_hz));
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9));
  for (auto next = start; next < end; next += period) {
    std::this_thread::sleep_until(next);
    send(sim::realtime_ns());
  }
}

template <typename Sample>
Result run_case(const Case& c, const dds_topic_descriptor_t* type, const std::string& self,
                const std::string& bridge_tool, bool via_bridge, double seconds, bool reliable) {
  const std::string name = "/bench_bridge_" + std::to_string(::getpid()) + (via_bridge ? "_b" : "_p");
  CycloneParticipant participant;
  Receiver<Sample> receiver(participant, type, "rt" + name, reliable);
  std::uint64_t sent = 0;
  double cpu = 0;
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
    const double cpu0 = cpu_seconds(bridge.pid());
    pace(c, seconds, [&](std::int64_t stamp) {
      // The producer's cost is not the bridge's: only the first byte changes per frame.
      sim::Loan loan = writer->loan();
      loan.bytes()[0] = static_cast<std::byte>(sent & 0xff);
      if (std::move(loan).commit(c.layout.min_capacity(), stamp) == sim::WriteStatus::ok) ++sent;
    });
    std::this_thread::sleep_for(500ms);  // the last messages in flight
    cpu = cpu_seconds(bridge.pid()) - cpu0;
    bridge.signal(SIGTERM);
    bridge.wait();
    (void)sim::destroy(name, true);
  } else {
    std::vector<std::string> argv = {self, "--plain-publisher", name, "--case", c.name,
                                     "--seconds", std::to_string(seconds)};
    if (reliable) argv.push_back("--reliable");
    sim::testing::Process publisher(argv);
    const auto started = publisher.wait_for_line("started");
    const double cpu0 = cpu_seconds(publisher.pid());
    const auto done = publisher.wait_for_line("sent", std::chrono::milliseconds(static_cast<int>(seconds * 1000) + 30'000));
    cpu = cpu_seconds(publisher.pid()) - cpu0;
    if (done) sent = std::stoull(done->substr(done->find(' ') + 1));
    std::this_thread::sleep_for(500ms);
    publisher.signal(SIGTERM);
    publisher.wait();
    (void)started;
  }
  return summarize(receiver.latencies_ms(), receiver.bytes(), sent, seconds, cpu);
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

void enter_private_network() {
  if (unshare(CLONE_NEWNET) != 0) {
    std::fprintf(stderr, "bench_bridge: not root: running on this machine's interfaces\n");
    return;
  }
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ifreq request{};
  std::snprintf(request.ifr_name, IFNAMSIZ, "lo");
  ioctl(fd, SIOCGIFFLAGS, &request);
  request.ifr_flags = static_cast<short>(request.ifr_flags | IFF_UP | IFF_MULTICAST);
  ioctl(fd, SIOCSIFFLAGS, &request);
  close(fd);
  std::system("ip route add 224.0.0.0/4 dev lo 2>/dev/null");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"SIM → sim_dds_bridge → Cyclone DDS against a plain Fast DDS publisher, same run.",
               "bench_bridge"};
  double seconds = 5;
  bool reliable = false;
  std::string only;
  std::string plain_name;
  app.add_option("--seconds", seconds, "seconds per case and path")->check(CLI::PositiveNumber);
  app.add_flag("--reliable", reliable, "reliable QoS instead of best effort");
  app.add_option("--case", only, "run only this case");
  app.add_option("--plain-publisher", plain_name, "(internal) be the plain publisher of this topic");
  CLI11_PARSE(app, argc, argv);

  for (const Case& c : paper_cases()) {
    if (!plain_name.empty() && c.name == only) return plain_publisher(plain_name, c, seconds, reliable);
  }
  if (!plain_name.empty()) return 2;
  enter_private_network();
  const std::string self = "/proc/self/exe";
  char path[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
  const std::string me = n > 0 ? std::string(path, static_cast<std::size_t>(n)) : self;

  std::printf("| case | path | QoS | received/sent | mean ms | p99 ms | MB/s | publisher CPU %% |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Case& c : paper_cases()) {
    if (!only.empty() && c.name != only) continue;
    for (bool via_bridge : {false, true}) {
      const Result r = c.layout.kind == sim::LayoutKind::points
                           ? run_case<sensor_msgs_msg_dds__PointCloud2_>(
                                 c, &sensor_msgs_msg_dds__PointCloud2__desc, me, SIM_DDS_BRIDGE,
                                 via_bridge, seconds, reliable)
                           : run_case<sensor_msgs_msg_dds__Image_>(
                                 c, &sensor_msgs_msg_dds__Image__desc, me, SIM_DDS_BRIDGE,
                                 via_bridge, seconds, reliable);
      std::printf("| %s | %s | %s | %llu/%llu | %.2f | %.2f | %.1f | %.1f |\n", c.name.c_str(),
                  via_bridge ? "SIM → bridge" : "plain Fast DDS", reliable ? "reliable" : "best effort",
                  static_cast<unsigned long long>(r.received), static_cast<unsigned long long>(r.sent),
                  r.mean_ms, r.p99_ms, r.mb_per_s, r.cpu_percent);
      std::fflush(stdout);
    }
  }
  return 0;
}
