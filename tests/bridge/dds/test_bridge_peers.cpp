// SPDX-License-Identifier: Apache-2.0
// ROS 2 nodes on rmw_cyclonedds come and go, each in a process of its own (the ros2 daemon, a
// `ros2 topic echo`, `ros2 topic hz`), while the bridge publishes. Against a real ROS 2 the
// bridge used to abort in Fast DDS 2.9.1's statistics code when one joined
// (docs/ros2-interop.md, "Defect: the bridge aborts in Fast DDS"). Each node here is this test
// program run again with --ros-node: a Cyclone DDS participant that reads the bridge's latched
// topics the way a ROS 2 node does, in the same private network namespace.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bridge_test.hpp"
#include "cyclone.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

using namespace bridge_test;

constexpr EndpointQos latched{.reliable = true, .transient_local = true, .depth = 1};

std::string g_self;  // this program, to start the nodes

// Cyclone DDS as ROS 2 Jazzy's rmw_cyclonedds runs it on loopback with multicast: a participant
// index of its own, so its metatraffic (7410 + 2i) and user data (7411 + 2i) unicast locators
// differ, and every reader also names the default multicast locator 239.255.0.1:7401.
constexpr const char* ros2_cyclone_config =
    "<General><Interfaces><NetworkInterface name=\"lo\" multicast=\"true\"/></Interfaces>"
    "<AllowMulticast>true</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex></Discovery>";

// The node: reads ros_discovery_info and /tf_static (reliable, transient local, as ROS 2 does),
// the images and their camera_info (sensor data QoS) until it has one message of each, says
// "joined", then stays until it is ended (`stay`) or leaves at once. Exit 1 when a message did
// not come.
int run_ros_node(const std::string& camera, bool stay) {
  setenv("CYCLONEDDS_URI", ros2_cyclone_config, 1);
  CycloneParticipant node;
  CycloneReader<Graph> graph(node, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                             "ros_discovery_info", latched);
  CycloneReader<Image> images(node, &sensor_msgs_msg_dds__Image__desc, "rt" + camera + "/image_raw");
  CycloneReader<CameraInfo> info(node, &sensor_msgs_msg_dds__CameraInfo__desc, "rt" + camera + "/camera_info");
  CycloneReader<TfMessage> tf(node, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched);
  if (!graph.take([](const Graph&) {}) || !tf.take([](const TfMessage&) {}) ||
      !images.take([](const Image&) {}) || !info.take([](const CameraInfo&) {})) {
    std::fprintf(stderr, "the node did not receive ros_discovery_info, /tf_static, an image and its camera_info\n");
    return 1;
  }
  std::printf("joined\n");
  std::fflush(stdout);
  while (stay) pause();
  return 0;
}

Process start_node(const std::string& camera, const char* how) {
  return Process({g_self, "--ros-node", camera, how});
}

sim::SensorInfo calibrated_camera() {
  sim::SensorInfo s;
  s.frame_id = "camera_optical";
  s.mounting = sim::Mounting{{1.25, 0.0, 1.5}, {-0.5, 0.5, -0.5, 0.5}};
  sim::CameraCalibration c;
  c.width = 16;
  c.height = 12;
  c.k = {500, 0, 8, 0, 500, 6, 0, 0, 1};
  c.p = {500, 0, 8, 0, 0, 500, 6, 0, 0, 0, 1, 0};
  s.calibration = c;
  return s;
}

// True while the process `pid` runs (the child is not reaped: its Process still reads its exit).
bool running(pid_t pid) {
  siginfo_t info{};
  return waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == 0;
}

// The bridge's reliable writers (ros_discovery_info, /tf_static) each have a reader in every
// node. With two or more, Fast DDS selects the readers' shared multicast locator; when one more
// reader matches, it sends that reader alone a heartbeat to its unicast locator. A node with a
// participant index has a unicast locator of its own for data (7411 + 2i), which Fast DDS 2.9.1
// had opened no output channel for, and it aborted in OutputTrafficManager.hpp:87. The nodes have
// no writers: a real ROS 2 node's ros_discovery_info writer lets the bridge's graph reader open
// that locator, when Fast DDS happens to match the writer before the reader. One node stays; two
// more join in each round, get everything and leave (their indices and locators are reused).
TEST(BridgePeers, Ros2NodesJoiningInTheirOwnProcessesNeverEndTheBridge) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard camera(unique_name("peers"));
  sim::StreamSpec spec{.name = camera.name};
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::mono8));
  spec.sensor = calibrated_camera();
  FramePump frames(spec);
  ASSERT_TRUE(frames.ok()) << frames.error();
  Process bridge = start_bridge({"--publish", camera.name});
  ASSERT_FALSE(wait_counter(bridge, "/tf_static", "bridged", 1).empty()) << bridge.err();

  Process staying = start_node(camera.name, "stay");
  ASSERT_TRUE(staying.wait_for_line("joined", 60s)) << staying.err() << bridge.err();
  for (int round = 0; round < 2; ++round) {
    Process first = start_node(camera.name, "leave");
    Process second = start_node(camera.name, "leave");
    const int first_exit = first.wait();
    const int second_exit = second.wait();
    ASSERT_TRUE(running(bridge.pid())) << "the bridge ended (exit " << bridge.wait() << ") while nodes joined in round "
                                       << round << ":\n" << bridge.err();
    EXPECT_EQ(first_exit, 0) << "round " << round << ": " << first.err();
    EXPECT_EQ(second_exit, 0) << "round " << round << ": " << second.err();
  }
  staying.signal(SIGTERM);
  (void)staying.wait();
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--ros-node") == 0) {
    return run_ros_node(argv[2], std::strcmp(argv[3], "stay") == 0);
  }
  g_self = std::filesystem::read_symlink("/proc/self/exe");
  return bridge_test::run_tests(argc, argv);
}
