// SPDX-License-Identifier: Apache-2.0
// Every program keeps the one exit-code contract on a wrong command line: exit code 2 and one
// sentence on stderr that starts with the program's name, before any device, port or file is
// opened; --help exits 0.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sim_test/process.hpp"

namespace {

using sim::testing::run;

struct BadCommandLine {
  std::string program;              // its path
  std::vector<std::string> arguments;
  std::string expected;             // a part of the sentence
};

std::string name_of(const std::string& path) { return path.substr(path.rfind('/') + 1); }

void expect_usage_error(const BadCommandLine& bad) {
  std::vector<std::string> argv = {bad.program};
  argv.insert(argv.end(), bad.arguments.begin(), bad.arguments.end());
  const auto result = run(argv);
  std::string shown;
  for (const auto& a : bad.arguments) shown += " " + a;
  EXPECT_EQ(result.code, 2) << name_of(bad.program) << shown << "\n" << result.err;
  EXPECT_EQ(result.err.rfind(name_of(bad.program) + ": ", 0), 0U) << shown << "\n" << result.err;
  EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "one line:" << shown << "\n"
                                                          << result.err;
  EXPECT_NE(result.err.find(bad.expected), std::string::npos) << shown << "\n" << result.err;
}

// Every built program, with the arguments that make a valid call apart from the one at fault.
struct Program {
  std::string path;
  std::vector<std::string> valid;        // arguments of an otherwise valid call
  std::string stream_option;             // "" for a positional stream, "-" for none
};

std::vector<Program> programs() {
  std::vector<Program> list;
#ifdef SIM_PROGRAM_sim_echo
  list.push_back({SIM_PROGRAM_sim_echo, {}, ""});
#endif
#ifdef SIM_PROGRAM_sim_ls
  list.push_back({SIM_PROGRAM_sim_ls, {}, ""});
#endif
#ifdef SIM_PROGRAM_sim_rm
  list.push_back({SIM_PROGRAM_sim_rm, {}, ""});
#endif
#ifdef SIM_PROGRAM_sim_dump
  list.push_back({SIM_PROGRAM_sim_dump, {}, ""});
#endif
#ifdef SIM_PROGRAM_sim_replay_video
  list.push_back({SIM_PROGRAM_sim_replay_video, {"/nonexistent/video.avi"}, "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_replay_serial
  list.push_back({SIM_PROGRAM_sim_replay_serial, {"/nonexistent/l2.bin", "--model", "L2"},
                  "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_replay_pcap
  list.push_back({SIM_PROGRAM_sim_replay_pcap,
                  {"/nonexistent/capture.pcap", "--calibration", "/nonexistent/c.csv"},
                  "--stream"});
  list.push_back({SIM_PROGRAM_sim_replay_pcap,
                  {"/nonexistent/capture.pcap", "--model", "unitree-l2"}, "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_camera_v4l2
  list.push_back({SIM_PROGRAM_sim_camera_v4l2, {"/dev/video-sim-missing"}, "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_camera_aravis
  list.push_back({SIM_PROGRAM_sim_camera_aravis, {"sim-no-such-camera"}, "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_lidar_unitree
  list.push_back({SIM_PROGRAM_sim_lidar_unitree, {"--model", "L2", "--udp-port", "0"}, "--stream"});
#endif
#ifdef SIM_PROGRAM_sim_lidar_hesai
  // A free port on loopback opens fine; the missing calibration fails only after it (exit 1).
  list.push_back({SIM_PROGRAM_sim_lidar_hesai,
                  {"--calibration", "/nonexistent/c.csv", "--bind", "127.0.0.1", "--port", "0"},
                  "--stream"});
#endif
  return list;
}

TEST(EveryProgram, AnUnknownOptionIsExitCodeTwoWithOneSentence) {
  for (const auto& p : programs()) {
    std::vector<std::string> args = p.valid;
    if (p.stream_option.empty()) args.push_back("/lidar_top");
    if (p.stream_option.starts_with("--")) args.insert(args.end(), {p.stream_option, "/lidar_top"});
    args.push_back("--no-such-option");
    expect_usage_error({p.path, args, "--no-such-option"});
  }
}

TEST(EveryProgram, AStreamNameWithoutItsSlashIsRefusedBeforeAnythingIsOpened) {
  for (const auto& p : programs()) {
    if (p.stream_option == "-") continue;
    std::vector<std::string> args = p.valid;
    if (!p.stream_option.empty()) args.push_back(p.stream_option);
    args.push_back("lidar_top");
    // The device, port or file named in the valid part does not exist: a program that opened it
    // first would fail with exit code 1 and another sentence.
    expect_usage_error({p.path, args, "must start with '/'"});
  }
}

// Every driver and replay (the programs that write a stream) takes the sensor options: a frame
// name ROS 2 would refuse, a mounting that is not a number, and (cameras) a calibration file
// that cannot be read are usage errors, found before the device, port or file is opened.
TEST(EveryProgram, ABadFrameMountingOrCameraInfoIsRefusedBeforeAnythingIsOpened) {
  for (const auto& p : programs()) {
    if (p.stream_option != "--stream") continue;
    std::vector<std::string> args = p.valid;
    args.insert(args.end(), {"--stream", "/lidar_top"});
    auto with = [&](std::vector<std::string> extra) {
      std::vector<std::string> all = args;
      all.insert(all.end(), extra.begin(), extra.end());
      return all;
    };
    expect_usage_error({p.path, with({"--frame-id", "lidar top"}), "--frame-id"});
    expect_usage_error({p.path, with({"--parent-frame", "/base_link"}), "--parent-frame"});
    expect_usage_error({p.path, with({"--yaw", "nan"}), "finite"});
    const std::string name = name_of(p.path);
    if (name == "sim_replay_video" || name == "sim_camera_v4l2" || name == "sim_camera_aravis") {
      expect_usage_error({p.path, with({"--camera-info", "/nonexistent/front.yaml"}),
                          "/nonexistent/front.yaml"});
      expect_usage_error({p.path, with({"--camera-info", "package://cam/front.yaml"}), "file://"});
    }
  }
}

TEST(EveryProgram, HelpExitsZeroAndShowsTheExitCodes) {
  for (const auto& p : programs()) {
    std::vector<std::string> argv = {p.path};
    argv.insert(argv.end(), p.valid.begin(), p.valid.end());
    argv.push_back("--help");
    const auto result = run(argv);
    EXPECT_EQ(result.code, 0) << name_of(p.path) << "\n" << result.err;
    EXPECT_NE(result.out.find("Exit codes: 0"), std::string::npos) << name_of(p.path);
  }
}

TEST(EveryProgram, ANegativeCountAnImpossiblePriorityOrAnUnknownTrustIsAUsageError) {
#ifdef SIM_PROGRAM_sim_dump
  expect_usage_error({SIM_PROGRAM_sim_dump, {"/lidar_top", "--count", "-1"}, "--count"});
#endif
#ifdef SIM_PROGRAM_sim_echo
  expect_usage_error({SIM_PROGRAM_sim_echo, {"/lidar_top", "--rt-priority", "100"}, "--rt-priority"});
#endif
#ifdef SIM_PROGRAM_sim_dump
  expect_usage_error({SIM_PROGRAM_sim_dump, {"/lidar_top", "--trust-owner", "sim-no-such-user"},
                      "sim-no-such-user"});
#endif
#ifdef SIM_PROGRAM_sim_echo
  expect_usage_error({SIM_PROGRAM_sim_echo, {"/lidar_top", "--trust-group", "sim-no-such-group"},
                      "sim-no-such-group"});
#endif
  // The programs that read streams for others (recorder, live view, DDS bridge) take them too.
#ifdef SIM_PROGRAM_sim_record
  expect_usage_error({SIM_PROGRAM_sim_record,
                      {"-o", "/nonexistent/never.mcap", "/lidar_top", "--trust-owner", "sim-no-such-user"},
                      "sim-no-such-user"});
#endif
#ifdef SIM_PROGRAM_sim_foxglove
  expect_usage_error({SIM_PROGRAM_sim_foxglove, {"--port", "0", "--trust-group", "sim-no-such-group"},
                      "sim-no-such-group"});
#endif
#ifdef SIM_PROGRAM_sim_dds_bridge
  expect_usage_error({SIM_PROGRAM_sim_dds_bridge,
                      {"--publish", "/lidar_top", "--trust-owner", "sim-no-such-user"},
                      "sim-no-such-user"});
#endif
#ifdef SIM_PROGRAM_sim_lidar_unitree
  expect_usage_error({SIM_PROGRAM_sim_lidar_unitree,
                      {"--model", "L1", "--stream", "/lidar_top"}, "--serial"});
  expect_usage_error({SIM_PROGRAM_sim_lidar_unitree,
                      {"--model", "L3", "--stream", "/lidar_top"}, "unknown model"});
#endif
#ifdef SIM_PROGRAM_sim_lidar_hesai
  expect_usage_error({SIM_PROGRAM_sim_lidar_hesai,
                      {"--calibration", "/nonexistent/c.csv", "--model", "Velodyne"}, "unknown model"});
  expect_usage_error({SIM_PROGRAM_sim_lidar_hesai,
                      {"--calibration", "/nonexistent/c.csv", "--bind", "not-an-ip"},
                      "is not an IP address"});
  expect_usage_error({SIM_PROGRAM_sim_lidar_hesai,
                      {"--calibration", "/nonexistent/c.csv", "--multicast-group", "10.0.0.1"},
                      "is not a multicast group address"});
  expect_usage_error({SIM_PROGRAM_sim_lidar_hesai, {"--stream", "/lidar_top"}, "no calibration"});
#endif
}

}  // namespace
