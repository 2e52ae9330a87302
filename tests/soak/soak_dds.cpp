// SPDX-License-Identifier: Apache-2.0
// sim_soak_dds: sim_dds_bridge and a Cyclone DDS subscriber (another vendor, as a remote ROS 2
// node would be) in a private network namespace of their own, for the soak.
//
//   sim_soak_dds TOPIC… -- BRIDGE [bridge options…]
//
// Moves itself into a new network namespace (loopback with multicast), starts the bridge there as
// its child, and subscribes to every TOPIC ("/lidar_top": the ROS 2 topic rt/lidar_top) as
// sensor_msgs/PointCloud2. One JSON line per second: clouds per topic, clouds out of order (stamp
// not above the previous one) or malformed (data not width × point_step), and the bridge's pid.
// SIGTERM ends the bridge with SIGTERM and reports its exit code; the namespace goes with the two
// processes. Exit 0 only if the bridge lived until asked to stop and then exited 0.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cyclone.hpp"
#include "sim_test/network.hpp"

namespace {

using namespace std::chrono_literals;
using Cloud = sensor_msgs_msg_dds__PointCloud2_;

std::atomic<bool> g_stop{false};

struct TopicCounters {
  std::uint64_t clouds = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t malformed = 0;
  std::int64_t last_stamp = 0;
};

// The bridge dies with this process, however it ends (nothing is left behind).
pid_t start_bridge(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);  // the parent died before prctl
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// Waits up to `limit` for the bridge to exit; its wait status, or -1 if it did not.
int reap(pid_t pid, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(20ms);
  }
  return -1;
}

std::string describe(int status) {
  if (status == -1) return "did not exit within 15 s of SIGTERM";
  if (WIFEXITED(status)) return "exit " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("killed by ") + strsignal(WTERMSIG(status));
  return "ended";
}

void print_stats(pid_t bridge, const std::map<std::string, TopicCounters>& topics, const char* extra) {
  std::string line = "{\"kind\":\"stats\",\"role\":\"dds\",\"bridge_pid\":" + std::to_string(bridge) + extra +
                     ",\"topics\":{";
  bool first = true;
  for (const auto& [name, c] : topics) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "%s\"%s\":{\"clouds\":%" PRIu64 ",\"out_of_order\":%" PRIu64 ",\"malformed\":%" PRIu64 "}",
                  first ? "" : ",", name.c_str(), c.clouds, c.out_of_order, c.malformed);
    line += text;
    first = false;
  }
  line += "}}";
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

void check_cloud(const Cloud& cloud, TopicCounters& c) {
  ++c.clouds;
  const std::int64_t stamp = std::int64_t{cloud.header.stamp.sec} * 1'000'000'000 + cloud.header.stamp.nanosec;
  if (c.last_stamp != 0 && stamp <= c.last_stamp) ++c.out_of_order;
  c.last_stamp = stamp;
  if (cloud.data._length != std::uint64_t{cloud.width} * cloud.height * cloud.point_step) ++c.malformed;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> topics, bridge_argv;
  bool after_dashes = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--" && !after_dashes) {
      after_dashes = true;
    } else {
      (after_dashes ? bridge_argv : topics).push_back(a);
    }
  }
  if (topics.empty() || bridge_argv.empty()) {
    std::fprintf(stderr, "sim_soak_dds: usage: sim_soak_dds TOPIC... -- BRIDGE [options...]\n");
    return 2;
  }
  // First, before any thread exists (Cyclone starts threads): unshare moves only this thread.
  if (auto why = sim::testing::enter_private_network(sim::testing::Multicast::on)) {
    std::fprintf(stderr, "sim_soak_dds: %s\n", why->c_str());
    return 1;
  }
  struct sigaction action {};
  action.sa_handler = [](int) { g_stop = true; };
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);

  const pid_t bridge = start_bridge(bridge_argv);
  if (bridge < 0) {
    std::fprintf(stderr, "sim_soak_dds: cannot start %s\n", bridge_argv[0].c_str());
    return 1;
  }
  std::map<std::string, TopicCounters> counters;
  int result = 0;
  {
    sim::testing::CycloneParticipant participant;
    std::vector<std::unique_ptr<sim::testing::CycloneReader<Cloud>>> readers;
    for (const auto& t : topics) {
      readers.push_back(std::make_unique<sim::testing::CycloneReader<Cloud>>(
          participant, &sensor_msgs_msg_dds__PointCloud2__desc, "rt" + t));
      counters[t];
    }
    auto next_print = std::chrono::steady_clock::now();
    int status = 0;
    while (!g_stop) {
      for (std::size_t i = 0; i < readers.size(); ++i) {
        while (readers[i]->take([&](const Cloud& c) { check_cloud(c, counters[topics[i]]); }, 0ms)) {
        }
      }
      std::this_thread::sleep_for(20ms);
      if (waitpid(bridge, &status, WNOHANG) == bridge) {  // nobody asked it to stop
        print_stats(bridge, counters, (",\"bridge_ended\":\"" + describe(status) + "\"").c_str());
        return 1;
      }
      if (std::chrono::steady_clock::now() >= next_print) {
        print_stats(bridge, counters, "");
        next_print += 1s;
      }
    }
  }
  kill(bridge, SIGTERM);
  const int status = reap(bridge, 15s);
  if (status == -1) kill(bridge, SIGKILL), reap(bridge, 5s);
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) result = 1;
  print_stats(bridge, counters, (",\"final\":true,\"bridge_exit\":\"" + describe(status) + "\"").c_str());
  return result;
}
