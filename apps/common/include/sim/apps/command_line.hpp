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
// (docs/build-times.md). A .cpp that adds its options through app() includes <CLI/CLI.hpp> itself;
// scripts/check-cli11-headers.py (ctest cli11_stays_out_of_headers) keeps it so.
#pragma once

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

class CommandLine {
 public:
  // `tool` prefixes every message ("sim_echo"); `description` is the first paragraph of --help.
  CommandLine(std::string tool, std::string description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;  // options point into it
  CommandLine& operator=(const CommandLine&) = delete;

  // The parser, to add a program's own options (the caller includes <CLI/CLI.hpp>).
  CLI::App& app() noexcept { return *app_; }
  const std::string& tool() const noexcept { return tool_; }

  // A stream name option ("--stream") or positional ("stream"), checked by the core's rules.
  CLI::Option* add_stream(std::string_view name, std::string& value, std::string_view help);
  // Several stream names (a positional list), each checked the same way.
  CLI::Option* add_streams(std::string_view name, std::vector<std::string>& values,
                           std::string_view help);
  // Options that need no CLI11 in the caller (a translation unit that includes <CLI/CLI.hpp>
  // costs about 10 CPU-seconds at -O3): a flag, and a text value that `problem` checks (it returns
  // what is wrong, empty when nothing), shown as `type_name`. An empty `group`: the default one.
  void add_flag(std::string_view name, bool& value, std::string_view help,
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
