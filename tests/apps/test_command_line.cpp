// SPDX-License-Identifier: Apache-2.0
// The command line every program shares: exit codes, stream names refused before anything is
// opened, and the YAML config file merged under the command line.
#include <CLI/CLI.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
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

// add_flag and add_text: the verbs a file uses when it should not compile CLI11 itself.
TEST(CommandLine, AFlagAndACheckedTextAreSetAndShownInTheirGroup) {
  CommandLine cli("sim_test", "test");
  bool force = false;
  std::string socket = "/var/run/ptp4l";
  cli.add_flag("--force", force, "remove anyway");
  cli.add_text("--socket", socket, "the socket", "PATH", {}, "Clock");
  EXPECT_FALSE(parse(cli, {"sim_test", "--force", "--socket", "/tmp/s"}).has_value());
  EXPECT_TRUE(force);
  EXPECT_EQ(socket, "/tmp/s");

  CommandLine help_cli("sim_test", "test");
  help_cli.add_text("--socket", socket, "the socket", "PATH", {}, "Clock");
  testing::internal::CaptureStdout();
  EXPECT_EQ(parse(help_cli, {"sim_test", "--help"}), std::optional<int>(sim::apps::kExitOk));
  const std::string help = testing::internal::GetCapturedStdout();
  EXPECT_NE(help.find("Clock:"), std::string::npos) << help;
  EXPECT_NE(help.find("PATH=/tmp/s"), std::string::npos) << help;
}

TEST(CommandLine, ATextItsCheckRefusesIsAUsageErrorThatSaysWhy) {
  CommandLine cli("sim_test", "test");
  std::string name;
  cli.add_text("--name", name, "a name", "NAME", [](const std::string& text) {
    return text.size() > 3 ? "the name is longer than 3 characters" : std::string();
  });
  testing::internal::CaptureStderr();
  const auto code = parse(cli, {"sim_test", "--name", "toolong"});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("the name is longer than 3 characters"), std::string::npos) << message;
  EXPECT_TRUE(name.empty());
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

// The Hesai config files (config/hesai/*.yaml) name the calibration beside them: a relative
// file name in a config file is relative to the file's folder; on the command line, to the
// working folder; an absolute one stays.
TEST(ConfigFile, ARelativePathOptionIsTakenFromTheFilesFolder) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sim_apps_test_dir_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "lidar.yaml").string();
  std::ofstream(file) << "calibration: unit.csv\nfiretimes: /etc/sim/firetimes.csv\n"
                         "label: notes.txt\n";
  auto parse_with = [&](std::vector<std::string> extra) {
    CommandLine cli("sim_test", "test");
    cli.add_config_file({"calibration", "firetimes"});
    std::string calibration, firetimes, label;
    cli.app().add_option("--calibration", calibration, "file");
    cli.app().add_option("--firetimes", firetimes, "file");
    cli.app().add_option("--label", label, "not a file");
    std::vector<std::string> words = {"sim_test", "--config", file};
    words.insert(words.end(), extra.begin(), extra.end());
    EXPECT_FALSE(parse(cli, words).has_value());
    return std::vector<std::string>{calibration, firetimes, label};
  };
  const auto from_file = parse_with({});
  EXPECT_EQ(from_file[0], (dir / "unit.csv").string());
  EXPECT_EQ(from_file[1], "/etc/sim/firetimes.csv");
  EXPECT_EQ(from_file[2], "notes.txt");  // not a path option: as written
  const auto overridden = parse_with({"--calibration", "other.csv"});
  EXPECT_EQ(overridden[0], "other.csv");  // the command line's is relative to the working folder
  std::filesystem::remove_all(dir);
}

// The Hesai config files say `keep_zero_distance: false`: a flag set to false in the file stays
// off, true turns it on, the command line still turns it on, and a value that is no boolean is
// a usage error that names the option.
TEST(ConfigFile, AFlagIsSetByTrueOrFalseInTheFile) {
  TempFile file("keep_zero_distance: false\npartial_frames: true\nchecksum: false\n");
  CommandLine cli("sim_test", "test");
  cli.add_config_file();
  bool keep_zero_distance = false, partial_frames = false, checksum = false;
  cli.app().add_flag("--keep-zero-distance", keep_zero_distance, "flag");
  cli.app().add_flag("--partial-frames", partial_frames, "flag");
  cli.app().add_flag("--checksum", checksum, "flag");
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", file.path(), "--checksum"}).has_value());
  EXPECT_FALSE(keep_zero_distance);
  EXPECT_TRUE(partial_frames);
  EXPECT_TRUE(checksum);

  TempFile bad("keep_zero_distance: maybe\n");
  CommandLine strict("sim_test", "test");
  strict.add_config_file();
  bool flag = false;
  strict.app().add_flag("--keep-zero-distance", flag, "flag");
  testing::internal::CaptureStderr();
  const auto code = parse(strict, {"sim_test", "--config", bad.path()});
  const std::string message = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, std::optional<int>(sim::apps::kExitUsage));
  EXPECT_NE(message.find("keep-zero-distance"), std::string::npos) << message;
  EXPECT_FALSE(flag);
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
