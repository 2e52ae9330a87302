// SPDX-License-Identifier: Apache-2.0
// --ptp4l-socket, the one option every program that reads the host's clock takes: on the command
// line, in a config file (relative to the file), and a path no Unix socket can have refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "sim/apps/host_clock_options.hpp"

namespace {

using sim::apps::CommandLine;

std::optional<int> parse(CommandLine& cli, std::vector<std::string> words) {
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return cli.parse(static_cast<int>(argv.size()), argv.data());
}

TEST(HostClockOptions, Ptp4lSocketIsEmptyUnlessGivenSoTheDefaultsAreTried) {
  CommandLine cli("sim_test", "test");
  sim::timing::HostClockOptions options;
  sim::apps::add_host_clock_options(cli, options);
  ASSERT_FALSE(parse(cli, {"sim_test"}));
  EXPECT_EQ(options.ptp4l_socket, "");
  CommandLine given("sim_test", "test");
  sim::apps::add_host_clock_options(given, options);
  ASSERT_FALSE(parse(given, {"sim_test", "--ptp4l-socket", "/run/ptp4l-eth1"}));
  EXPECT_EQ(options.ptp4l_socket, "/run/ptp4l-eth1");
}

TEST(HostClockOptions, AConfigFilesRelativeSocketIsRelativeToTheFile) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("sim_host_clock_options_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const std::string config = (folder / "c.yaml").string();
  std::ofstream(config) << "ptp4l_socket: ptp/ptp4l\n";
  CommandLine cli("sim_test", "test");
  sim::timing::HostClockOptions options;
  sim::apps::add_host_clock_options(cli, options);
  cli.add_config_file();
  const auto exit = parse(cli, {"sim_test", "--config", config});
  std::filesystem::remove_all(folder);
  ASSERT_FALSE(exit);
  EXPECT_EQ(options.ptp4l_socket, (folder / "ptp/ptp4l").string());
}

TEST(HostClockOptions, ASocketPathTooLongForUnixSocketsIsAUsageError) {
  CommandLine cli("sim_test", "test");
  sim::timing::HostClockOptions options;
  sim::apps::add_host_clock_options(cli, options);
  const auto exit = parse(cli, {"sim_test", "--ptp4l-socket", "/" + std::string(120, 'x')});
  ASSERT_TRUE(exit);
  EXPECT_EQ(*exit, sim::apps::kExitUsage);
}

}  // namespace
