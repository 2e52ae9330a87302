// SPDX-License-Identifier: Apache-2.0
// The command line every SIM program shares (the way libcamera keeps src/apps/common): one
// --help style with every default shown the same way, an optional YAML --config file whose keys
// are the long option names (the command line wins over the file), stream names checked before
// anything is opened, --cpu/--rt-priority, and one exit-code contract:
//   0 done, 1 failed at run time, 2 the command line (or the config file) was wrong.
// Every message is one sentence on stderr, prefixed with the program's name.
//
// CLI11 stays out of this header (and every other header): CLI11 2.x is header-only, and each
// translation unit that includes <CLI/CLI.hpp> compiles its validators, formatter and parser again
// (docs/build-times.md). Programs add their options through add_option() and the verbs of
// Option, which keep CLI11 in command_line.cpp alone; scripts/check-cli11.py (ctest
// cli11_stays_in_command_line_cpp) refuses it anywhere else, so a feature no verb offers becomes
// a new verb here rather than an include of <CLI/CLI.hpp> in a program.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/os.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace CLI {
class App;
class Option;
class Validator;
}  // namespace CLI

namespace sim::apps {

enum ExitCode : int {
  kExitOk = 0,       // done (also: stopped by SIGINT/SIGTERM, --help)
  kExitFailure = 1,  // failed at run time (a device, a file, a stream)
  kExitUsage = 2,    // wrong command line or config file
};

// CLI11 validator for stream names, using the core's naming rules (sim/names.hpp).
CLI::Validator stream_name_validator();
// A CLI11 validator from a function that returns the problem with a value (empty: none), so
// libraries can check values without knowing CLI11.
CLI::Validator validator(std::function<std::string(const std::string&)> problem,
                         std::string type_name);

class YamlConfig;

// An option a CommandLine added, refined without CLI11 in the caller. Each verb returns the
// option, so they chain:
//   cli.add_option("--port", port, "UDP port; 0 picks a free one").in_range(0, 65535);
// The checks are CLI11's own: --help and the usage errors say what they said when programs called
// CLI11 themselves.
class Option {
 public:
  // What is wrong with a value (a sentence), empty when nothing.
  using Problem = std::function<std::string(const std::string&)>;

  explicit Option(CLI::Option* option) noexcept : option_(option) {}

  // The option must be given (on the command line or in the config file).
  Option& required();
  // How --help names the value: "FILE" in "--calibration FILE".
  Option& type_name(std::string_view name);
  // A number from `low` to `high`, both included (CLI::Range). --help shows the type of the bounds
  // ("UINT in [1 - 1000]"), so T is the bounds' type: int, unsigned, std::uint64_t or double.
  template <class T>
  Option& in_range(T low, T high);
  // A number above 0 (CLI::PositiveNumber); 0 or above (CLI::NonNegativeNumber).
  Option& positive();
  Option& non_negative();
  // One of these words (CLI::IsMember; --help shows "{a,b}").
  Option& one_of(std::vector<std::string> words);
  // A value `problem` finds nothing wrong with; `shown`, when not empty, follows the type in
  // --help ("FLOAT:RATE").
  Option& check(Problem problem, std::string_view shown = {});
  // Given together with `other`: a usage error (either way round).
  Option& excludes(const Option& other);
  // Exactly `count` values (a list: --roi X Y WIDTH HEIGHT).
  Option& expected(int count);
  // `seen` gets each value given (on the command line or in the config file) while parse()
  // checks the values.
  Option& each(std::function<void(const std::string&)> seen);
  // A list option also takes several values in one word, split at `separator`
  // ("--ways a,b" as "--ways a --ways b"); each piece is checked on its own.
  Option& delimiter(char separator);
  // Parsed as any other but left out of --help: for the arguments a program passes to the copies
  // of itself it starts (sim_bench's --role).
  Option& hidden();

  // The same option (CommandLine::parse_order).
  bool operator==(const Option&) const = default;

 private:
  CLI::Option* option_;
};

class CommandLine {
 public:
  // `tool` prefixes every message ("sim_echo"); `description` is the first paragraph of --help.
  CommandLine(std::string tool, std::string description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;  // options point into it
  CommandLine& operator=(const CommandLine&) = delete;

  const std::string& tool() const noexcept { return tool_; }

  // A stream name option ("--stream") or positional ("stream"), checked by the core's rules.
  Option add_stream(std::string_view name, std::string& value, std::string_view help);
  // Several stream names (a positional list), each checked the same way.
  Option add_streams(std::string_view name, std::vector<std::string>& values,
                     std::string_view help);
  // An option ("--count,-n") or a positional ("file") that sets `value`; --help shows the value's
  // type and default ("--count INT=5"). command_line.cpp instantiates it for the types programs
  // use: std::string, int, unsigned, std::uint16_t, std::int64_t, std::uint64_t, float, double,
  // std::optional of int, std::uint16_t and double, and std::vector of std::string and int.
  template <class T>
  Option add_option(std::string_view name, T& value, std::string_view help);
  // An option that calls `set` with its value when given, and shows no default in --help (the
  // help text says what not giving it means). Instantiated for float.
  template <class T>
  Option add_option_function(std::string_view name, std::function<void(const T&)> set,
                             std::string_view help);
  // Options that need no CLI11 in the caller (a translation unit that includes <CLI/CLI.hpp>
  // costs about 10 CPU-seconds at -O3): a flag, and a text value that `problem` checks (it returns
  // what is wrong, empty when nothing), shown as `type_name`. An empty `group`: the default one.
  Option add_flag(std::string_view name, bool& value, std::string_view help,
                  std::string_view group = {});
  void add_text(std::string_view name, std::string& value, std::string_view help,
                std::string_view type_name,
                std::function<std::string(const std::string&)> problem = {},
                std::string_view group = {});
  // A number that may be left out (nullopt: not given), checked like add_text's value.
  void add_number(std::string_view name, std::optional<double>& value, std::string_view help,
                  std::string_view type_name,
                  std::function<std::string(const std::string&)> problem = {},
                  std::string_view group = {});
  // --config FILE: YAML keys set the options of the same long name ("rt_priority" or
  // "rt-priority" for --rt-priority); a map becomes a list of "key=value" items; options given on
  // the command line override the file. The options named in `path_options` ("calibration")
  // take file names: a relative one in the file is relative to the file's folder.
  void add_config_file(std::vector<std::string> path_options = {});
  // One more option whose value in a config file is a file name (before or after
  // add_config_file; add_sensor_options adds "camera-info").
  void add_path_option(std::string name);
  // --cpu N and --rt-priority P for the program's working thread.
  void add_placement(ThreadPlacement& placement);
  // --trust-owner USER and --trust-group GROUP for a program that reads streams: whose regions it
  // accepts besides its own user's (sim::Trust). Checked by parse(); an unknown user or group is
  // a usage error.
  void add_trust(Trust& trust);

  // Parses; an exit code when the program should end now (--help: 0; a bad argument: 2 after one
  // sentence on stderr), nothing when it should run.
  [[nodiscard]] std::optional<int> parse(int argc, char** argv);
  // After parse(): the options given on the command line (not in the config file), in the order
  // given, one entry per value: for options whose meaning depends on their order.
  std::vector<Option> parse_order() const;

  // Prints "tool: message" and returns kExitFailure (run-time failure) or kExitUsage.
  int fail(std::string_view message) const;
  int usage_error(std::string_view message) const;
  // An Error from the library: invalid names and arguments are usage errors, the rest failures.
  int fail(const Error& error) const;

  // Applies --cpu/--rt-priority; an exit code when it cannot (permission: 1, impossible value: 2).
  [[nodiscard]] std::optional<int> apply_placement(const ThreadPlacement& placement) const;

 private:
  std::string tool_;
  std::unique_ptr<CLI::App> app_;
  std::vector<std::string> path_options_;
  std::shared_ptr<YamlConfig> config_;  // set by add_config_file
  Trust* trust_ = nullptr;
  std::string trust_owner_;
  std::string trust_group_;
};

// Whether a status line belongs on stderr: it is a terminal and the user did not ask for quiet.
bool stderr_is_terminal() noexcept;

}  // namespace sim::apps
