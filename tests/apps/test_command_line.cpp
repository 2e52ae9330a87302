// SPDX-License-Identifier: Apache-2.0
// The command line every program shares: exit codes, stream names refused before anything is
// opened, and the YAML config file merged under the command line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"

namespace {

using sim::apps::CommandLine;

// Runs parse() on a command line given as words (the program name first).
std::optional<int> parse(CommandLine& cli, std::vector<std::string> words) {
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return cli.parse(static_cast<int>(argv.size()), argv.data());
}

// A config file that removes itself.
class TempFile {
 public:
  explicit TempFile(const std::string& text)
      : path_("/tmp/sim_apps_test_" + std::to_string(::getpid()) + "_" +
              std::to_string(counter_++) + ".yaml") {
    std::ofstream(path_) << text;
  }
  ~TempFile() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  std::string path_;
};

TEST(CommandLine, RefusesAStreamNameWithoutItsSlashAsAUsageErrorInOneLine) {
  CommandLine cli("sim_test", "test");
  std::string stream;
  cli.add_stream("--stream", stream, "stream");
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--stream", "lidar_top"});
  const std::string message = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, sim::apps::kExitUsage);
  EXPECT_EQ(message.rfind("sim_test: ", 0), 0U) << message;
  EXPECT_NE(message.find("must start with '/'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), message.size() - 1) << "one line: " << message;
}

TEST(CommandLine, AcceptsAGoodStreamNameAndRuns) {
  CommandLine cli("sim_test", "test");
  std::string stream;
  cli.add_stream("stream", stream, "stream");
  EXPECT_FALSE(parse(cli, {"sim_test", "/lidar_top"}).has_value());
  EXPECT_EQ(stream, "/lidar_top");
}

TEST(CommandLine, AnUnknownOptionIsAUsageError) {
  CommandLine cli("sim_test", "test");
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--no-such-option"});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("--no-such-option"), std::string::npos) << message;
}

TEST(CommandLine, HelpExitsZeroAndShowsDefaultsAndExitCodes) {
  CommandLine cli("sim_test", "test");
  int count = 5;
  cli.app().add_option("--count", count, "frames");
  testing::internal::CaptureStdout();
  const auto code = parse(cli, {"sim_test", "--help"});
  const std::string help = testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitOk));
  EXPECT_NE(help.find("INT=5"), std::string::npos) << help;
  EXPECT_NE(help.find("Exit codes: 0"), std::string::npos) << help;
}

TEST(CommandLine, AnImpossibleRealtimePriorityIsRefusedBeforeRunning) {
  CommandLine cli("sim_test", "test");
  sim::ThreadPlacement placement;
  cli.add_placement(placement);
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--rt-priority", "150"});
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
}

TEST(ConfigFile, SetsWhatTheCommandLineLeavesAndTheCommandLineWins) {
  TempFile file("stream: /from_file\nrt_priority: 20\nfps: 15\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  std::string stream;
  double fps = 30;
  sim::ThreadPlacement placement;
  cli.add_stream("--stream", stream, "stream");
  cli.app().add_option("--fps", fps, "rate");
  cli.add_placement(placement);
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", file.path(), "--fps", "60"}).has_value());
  EXPECT_EQ(stream, "/from_file");
  EXPECT_EQ(placement.rt_priority, std::optional<int>(20));
  EXPECT_EQ(fps, 60.0);
}

TEST(ConfigFile, AMapBecomesKeyValueItemsInFileOrderAndAListItsValues) {
  TempFile file("controls:\n  brightness: 128\n  gain: 3\nroi: [0, 0, 640, 480]\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  std::vector<std::string> controls;
  std::vector<int> roi;
  cli.app().add_option("--controls", controls, "name=value");
  cli.app().add_option("--roi", roi, "x y w h")->expected(4);
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", file.path()}).has_value());
  EXPECT_EQ(controls, (std::vector<std::string>{"brightness=128", "gain=3"}));
  EXPECT_EQ(roi, (std::vector<int>{0, 0, 640, 480}));
}

TEST(ConfigFile, AnUnknownKeyIsAUsageErrorThatNamesIt) {
  TempFile file("strem: /typo\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  std::string stream;
  cli.add_stream("--stream", stream, "stream");
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--config", file.path()});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("strem"), std::string::npos) << message;
}

TEST(ConfigFile, ABadStreamNameInTheFileIsRefusedLikeOnTheCommandLine) {
  TempFile file("stream: no_slash\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  std::string stream;
  cli.add_stream("--stream", stream, "stream");
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--config", file.path()});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("must start with '/'"), std::string::npos) << message;
}

TEST(ConfigFile, BrokenYamlIsAUsageErrorWithItsLine) {
  TempFile file("stream: [unclosed\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  std::string stream;
  cli.add_stream("--stream", stream, "stream");
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--config", file.path()});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("not valid YAML"), std::string::npos) << message;
}

TEST(ConfigFile, AMissingFileIsAUsageError) {
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--config", "/nonexistent/sim.yaml"});
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
}

}  // namespace
