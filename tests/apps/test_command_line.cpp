// SPDX-License-Identifier: Apache-2.0
// The command line every program shares: exit codes, stream names refused before anything is
// opened, and the YAML config file merged under the command line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "sim/apps/command_line.hpp"

namespace {

using sim::apps::CommandLine;
using sim::apps::kExitOk;
using sim::apps::kExitUsage;

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
  cli.add_option("--count", count, "frames");
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

// What parse() returned and what it said on stderr.
struct Parsed {
  std::optional<int> code;
  std::string message;
};

Parsed parse_capturing(CommandLine& cli, std::vector<std::string> words) {
  testing::internal::CaptureStderr();
  Parsed parsed;
  parsed.code = parse(cli, std::move(words));
  parsed.message = testing::internal::GetCapturedStderr();
  return parsed;
}

// What --help prints.
std::string help_of(CommandLine& cli) {
  testing::internal::CaptureStdout();
  const auto code = parse(cli, {"sim_test", "--help"});
  std::string help = testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, std::optional<int>(kExitOk));
  return help;
}

// The verbs of sim::apps::Option: CLI11's checks without CLI11 in the caller, so --help and the
// usage errors read as when the programs called CLI11 themselves.
TEST(CommandLineOption, ANumberOutsideItsRangeIsAUsageErrorInOneSentenceAndHelpShowsTheRange) {
  const auto build = [](CommandLine& cli, int& port) {
    cli.add_option("--port", port, "UDP port").in_range(0, 65535);
  };
  CommandLine cli("sim_test", "test");
  int port = 2368;
  build(cli, port);
  const Parsed parsed = parse_capturing(cli, {"sim_test", "--port", "70000"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message,
            "sim_test: --port: Value 70000 not in range 0 to 65535; see sim_test --help\n");

  CommandLine in_range("sim_test", "test");
  build(in_range, port);
  EXPECT_FALSE(parse(in_range, {"sim_test", "--port", "65535"}).has_value());
  EXPECT_EQ(port, 65535);

  CommandLine help_cli("sim_test", "test");
  build(help_cli, port);
  const std::string help = help_of(help_cli);
  EXPECT_NE(help.find("INT:INT in [0 - 65535]"), std::string::npos) << help;
}

TEST(CommandLineOption, APositiveNumberRefusesZeroAndANonNegativeOneRefusesLessThanZero) {
  CommandLine cli("sim_test", "test");
  double rate = 1.0;
  double start = 0.0;
  cli.add_option("--rate", rate, "speed").positive();
  cli.add_option("--start", start, "seconds").non_negative();
  const Parsed zero_rate = parse_capturing(cli, {"sim_test", "--rate", "0"});
  EXPECT_EQ(zero_rate.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(zero_rate.message, "sim_test: --rate: Value 0 is not above 0; see sim_test --help\n");

  CommandLine negative("sim_test", "test");
  negative.add_option("--rate", rate, "speed").positive();
  negative.add_option("--start", start, "seconds").non_negative();
  const Parsed negative_start = parse_capturing(negative, {"sim_test", "--start", "-1"});
  EXPECT_EQ(negative_start.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(negative_start.message, "sim_test: --start: Value -1 is not 0 or more; see sim_test --help\n");
  for (const char* not_a_number : {"nan", "inf", "1e999", "5x"}) {
    CommandLine refused("sim_test", "test");
    refused.add_option("--start", start, "seconds").non_negative();
    EXPECT_EQ(parse_capturing(refused, {"sim_test", "--start", not_a_number}).code,
              std::optional<int>(kExitUsage)) << not_a_number;
  }

  CommandLine good("sim_test", "test");
  good.add_option("--rate", rate, "speed").positive();
  good.add_option("--start", start, "seconds").non_negative();
  EXPECT_FALSE(parse(good, {"sim_test", "--rate", "0.5", "--start", "0"}).has_value());
  EXPECT_EQ(rate, 0.5);
  EXPECT_EQ(start, 0.0);
}

TEST(CommandLineOption, AWordNotAmongTheChoicesIsRefusedAndHelpListsThem) {
  const auto build = [](CommandLine& cli, std::string& returns) {
    cli.add_option("--returns", returns, "which").one_of({"both", "last", "strongest"});
  };
  CommandLine cli("sim_test", "test");
  std::string returns = "both";
  build(cli, returns);
  const Parsed parsed = parse_capturing(cli, {"sim_test", "--returns", "all"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message,
            "sim_test: --returns: all not in {both,last,strongest}; see sim_test --help\n");
  EXPECT_EQ(returns, "both");

  CommandLine good("sim_test", "test");
  build(good, returns);
  EXPECT_FALSE(parse(good, {"sim_test", "--returns", "last"}).has_value());
  EXPECT_EQ(returns, "last");

  CommandLine help_cli("sim_test", "test");
  build(help_cli, returns);
  const std::string help = help_of(help_cli);
  EXPECT_NE(help.find("TEXT:{both,last,strongest}"), std::string::npos) << help;
}

TEST(CommandLineOption, ACheckedValueIsRefusedWithTheChecksSentenceAndHelpShowsWhatItAdds) {
  const auto build = [](CommandLine& cli, double& rate) {
    cli.add_option("--max-rate", rate, "messages per second")
        .check([](const std::string& text) {
          return text == "0" || text == "5" ? std::string() : "--max-rate takes 0 or 5";
        }, "RATE");
  };
  CommandLine cli("sim_test", "test");
  double rate = 0;
  build(cli, rate);
  const Parsed parsed = parse_capturing(cli, {"sim_test", "--max-rate", "3"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message,
            "sim_test: --max-rate: --max-rate takes 0 or 5; see sim_test --help\n");
  EXPECT_EQ(rate, 0.0);

  CommandLine help_cli("sim_test", "test");
  build(help_cli, rate);
  const std::string help = help_of(help_cli);
  EXPECT_NE(help.find("FLOAT:RATE=0"), std::string::npos) << help;
}

TEST(CommandLineOption, ARequiredOptionLeftOutIsAUsageErrorThatNamesIt) {
  CommandLine cli("sim_test", "test");
  std::string model;
  cli.add_option("--model", model, "sensor model").required();
  const Parsed parsed = parse_capturing(cli, {"sim_test"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message, "sim_test: --model is required; see sim_test --help\n");
}

TEST(CommandLineOption, TwoOptionsThatExcludeEachOtherAreRefusedTogetherButNotAlone) {
  const auto build = [](CommandLine& cli, double& rate, bool& max_rate) {
    const auto rate_option = cli.add_option("--rate", rate, "speed").positive();
    cli.add_flag("--max-rate", max_rate, "no pacing").excludes(rate_option);
  };
  double rate = 1.0;
  bool max_rate = false;
  CommandLine cli("sim_test", "test");
  build(cli, rate, max_rate);
  const Parsed parsed = parse_capturing(cli, {"sim_test", "--rate", "2", "--max-rate"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_NE(parsed.message.find("--rate excludes --max-rate"), std::string::npos) << parsed.message;

  max_rate = false;
  CommandLine alone("sim_test", "test");
  build(alone, rate, max_rate);
  EXPECT_FALSE(parse(alone, {"sim_test", "--max-rate"}).has_value());
  EXPECT_TRUE(max_rate);
}

TEST(CommandLineOption, AListOfAnExpectedCountTakesExactlyThatMany) {
  CommandLine cli("sim_test", "test");
  std::vector<int> roi;
  cli.add_option("--roi", roi, "x y w h").expected(4);
  EXPECT_FALSE(parse(cli, {"sim_test", "--roi", "1", "2", "3", "4"}).has_value());
  EXPECT_EQ(roi, (std::vector<int>{1, 2, 3, 4}));

  CommandLine short_cli("sim_test", "test");
  std::vector<int> three;
  short_cli.add_option("--roi", three, "x y w h").expected(4);
  const Parsed parsed = parse_capturing(short_cli, {"sim_test", "--roi", "1", "2", "3"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_NE(parsed.message.find("--roi"), std::string::npos) << parsed.message;
}

TEST(CommandLineOption, EachValueGivenIsSeenFromTheCommandLineAndTheConfigFile) {
  std::vector<std::string> seen;
  const auto build = [&seen](CommandLine& cli, std::uint16_t& port) {
    cli.add_option("--port", port, "UDP port").each([&seen](const std::string& v) { seen.push_back(v); });
  };
  std::uint16_t port = 6201;
  CommandLine none("sim_test", "test");
  build(none, port);
  EXPECT_FALSE(parse(none, {"sim_test"}).has_value());
  EXPECT_TRUE(seen.empty());

  CommandLine given("sim_test", "test");
  build(given, port);
  EXPECT_FALSE(parse(given, {"sim_test", "--port", "0"}).has_value());
  EXPECT_EQ(seen, (std::vector<std::string>{"0"}));
  EXPECT_EQ(port, std::uint16_t{0});

  seen.clear();
  TempFile file("port: 7\n");
  CommandLine from_file("sim_test", "test");
  from_file.add_config_file();
  build(from_file, port);
  EXPECT_FALSE(parse(from_file, {"sim_test", "--config", file.path()}).has_value());
  EXPECT_EQ(seen, (std::vector<std::string>{"7"}));
  EXPECT_EQ(port, std::uint16_t{7});
}

TEST(CommandLineOption, ATypeNameNamesTheValueInHelp) {
  CommandLine cli("sim_test", "test");
  std::string calibration;
  cli.add_option("--calibration", calibration, "the unit's CSV").type_name("FILE");
  const std::string help = help_of(cli);
  EXPECT_NE(help.find("--calibration FILE"), std::string::npos) << help;
}

TEST(CommandLineOption, AnOptionFunctionGetsTheValueOnlyWhenGivenAndHelpShowsNoDefault) {
  std::optional<float> min_range;
  const auto build = [&min_range](CommandLine& cli) {
    cli.add_option_function<float>("--min-range", [&min_range](float v) { min_range = v; },
                                   "metres [0.3]")
        .type_name("FLOAT")
        .non_negative();
  };
  CommandLine none("sim_test", "test");
  build(none);
  EXPECT_FALSE(parse(none, {"sim_test"}).has_value());
  EXPECT_FALSE(min_range.has_value());

  CommandLine given("sim_test", "test");
  build(given);
  EXPECT_FALSE(parse(given, {"sim_test", "--min-range", "1.5"}).has_value());
  EXPECT_EQ(min_range, std::optional<float>(1.5F));

  CommandLine help_cli("sim_test", "test");
  build(help_cli);
  const std::string help = help_of(help_cli);
  EXPECT_NE(help.find("--min-range FLOAT:NONNEGATIVE "), std::string::npos) << help;
  EXPECT_EQ(help.find("NONNEGATIVE="), std::string::npos) << help;
}

// sim_dds_bridge pairs each --as with the --subscribe before it.
TEST(CommandLineOption, TheParseOrderListsTheOptionsAsGivenOneEntryPerValue) {
  CommandLine cli("sim_test", "test");
  std::vector<std::string> subscribes;
  std::vector<std::string> as;
  const auto subscribe = cli.add_option("--subscribe", subscribes, "topic");
  const auto as_option = cli.add_option("--as", as, "stream");
  ASSERT_FALSE(
      parse(cli, {"sim_test", "--subscribe", "/a", "--as", "/x", "--subscribe", "/b"}).has_value());
  const std::vector<sim::apps::Option> order = cli.parse_order();
  ASSERT_EQ(order.size(), 3U);
  EXPECT_TRUE(order[0] == subscribe);
  EXPECT_TRUE(order[1] == as_option);
  EXPECT_TRUE(order[2] == subscribe);
  EXPECT_FALSE(order[0] == as_option);
}

// bench_wait_set's --ways futex_waitv,notifier.
TEST(CommandLineOption, ADelimiterSplitsOneValueIntoSeveralAndChecksEachPiece) {
  const auto build = [](CommandLine& cli, std::vector<std::string>& ways) {
    cli.add_option("--ways", ways, "which").delimiter(',').one_of({"a", "b", "c"});
  };
  std::vector<std::string> ways;
  CommandLine cli("sim_test", "test");
  build(cli, ways);
  ASSERT_FALSE(parse(cli, {"sim_test", "--ways", "a,b", "--ways", "c"}).has_value());
  EXPECT_EQ(ways, (std::vector<std::string>{"a", "b", "c"}));

  std::vector<std::string> refused_ways;
  CommandLine refused("sim_test", "test");
  build(refused, refused_ways);
  const Parsed parsed = parse_capturing(refused, {"sim_test", "--ways", "a,x"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message, "sim_test: --ways: x not in {a,b,c}; see sim_test --help\n");
}

// sim_bench's --role, which it passes to the copies of itself it starts.
TEST(CommandLineOption, AHiddenOptionIsParsedButLeftOutOfHelp) {
  const auto build = [](CommandLine& cli, std::string& role, int& runs) {
    cli.add_option("--role", role, "").hidden().one_of({"writer", "reader"});
    cli.add_option("--runs", runs, "runs");
  };
  std::string role;
  int runs = 5;
  CommandLine cli("sim_test", "test");
  build(cli, role, runs);
  ASSERT_FALSE(parse(cli, {"sim_test", "--role", "reader"}).has_value());
  EXPECT_EQ(role, "reader");

  CommandLine refused("sim_test", "test");
  build(refused, role, runs);
  const Parsed parsed = parse_capturing(refused, {"sim_test", "--role", "judge"});
  EXPECT_EQ(parsed.code, std::optional<int>(kExitUsage));
  EXPECT_EQ(parsed.message, "sim_test: judge not in {writer,reader}; see sim_test --help\n");

  CommandLine help_cli("sim_test", "test");
  build(help_cli, role, runs);
  const std::string help = help_of(help_cli);
  EXPECT_EQ(help.find("--role"), std::string::npos) << help;
  EXPECT_NE(help.find("--runs"), std::string::npos) << help;
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
  cli.add_option("--fps", fps, "rate");
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
  cli.add_option("--controls", controls, "name=value");
  cli.add_option("--roi", roi, "x y w h").expected(4);
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
    cli.add_option("--calibration", calibration, "file");
    cli.add_option("--firetimes", firetimes, "file");
    cli.add_option("--label", label, "not a file");
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
  cli.add_flag("--keep-zero-distance", keep_zero_distance, "flag");
  cli.add_flag("--partial-frames", partial_frames, "flag");
  cli.add_flag("--checksum", checksum, "flag");
  ASSERT_FALSE(parse(cli, {"sim_test", "--config", file.path(), "--checksum"}).has_value());
  EXPECT_FALSE(keep_zero_distance);
  EXPECT_TRUE(partial_frames);
  EXPECT_TRUE(checksum);

  TempFile bad("keep_zero_distance: maybe\n");
  CommandLine strict("sim_test", "test");
  strict.add_config_file();
  bool flag = false;
  strict.add_flag("--keep-zero-distance", flag, "flag");
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
