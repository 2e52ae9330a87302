// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/command_line.hpp"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "sim/apps/yaml_config.hpp"
#include "sim/names.hpp"

namespace sim::apps {
namespace {

// CLI11 messages are fragments ("The following argument was not expected: --x"); close them as
// one sentence that says where to look.
std::string as_sentence(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ' || text.back() == '.')) {
    text.pop_back();
  }
  for (char& c : text) {
    if (c == '\n') c = ' ';
  }
  // CLI11 names no option that --help does not show (Option::hidden): ": x not in {a,b}".
  if (text.rfind(": ", 0) == 0) text.erase(0, 2);
  return text;
}

// CLI11's side of the --config file: YamlConfig reads it, CLI11 merges it with the command line.
class CliYamlConfig final : public CLI::Config {
 public:
  explicit CliYamlConfig(std::shared_ptr<YamlConfig> yaml) : yaml_(std::move(yaml)) {}

  // Writing a config file back (--write-config) is not offered.
  std::string to_config(const CLI::App*, bool, bool, std::string) const override { return {}; }
  // CLI11 reports a ConfigError as a usage error; parse() words it.
  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    auto entries = yaml_->read(input);
    if (!entries) throw CLI::ConfigError(entries.error().message);
    std::vector<CLI::ConfigItem> result;
    result.reserve(entries->size());
    for (ConfigEntry& entry : *entries) {
      CLI::ConfigItem item;
      item.name = std::move(entry.name);
      item.inputs = std::move(entry.inputs);
      result.push_back(std::move(item));
    }
    return result;
  }

 private:
  std::shared_ptr<YamlConfig> yaml_;
};

}  // namespace

CLI::Validator stream_name_validator() {
  return CLI::Validator([](std::string& name) { return stream_name_problem(name); }, "", "stream name");
}

CLI::Validator validator(std::function<std::string(const std::string&)> problem,
                         std::string type_name) {
  return CLI::Validator([problem = std::move(problem)](std::string& value) { return problem(value); },
                        "", std::move(type_name));
}

Option& Option::required() {
  option_->required();
  return *this;
}

Option& Option::type_name(std::string_view name) {
  option_->type_name(std::string(name));
  return *this;
}

template <class T>
Option& Option::in_range(T low, T high) {
  option_->check(CLI::Range(low, high));
  return *this;
}

template Option& Option::in_range<int>(int, int);
template Option& Option::in_range<unsigned>(unsigned, unsigned);
template Option& Option::in_range<std::uint64_t>(std::uint64_t, std::uint64_t);
template Option& Option::in_range<double>(double, double);

namespace {

// CLI11 2.1's PositiveNumber and NonNegativeNumber are ranges up to the largest double and print
// it in full (309 digits) when they refuse a value; these say the same in a sentence. The
// description ("POSITIVE") follows the type in --help, as CLI11's did.
CLI::Validator number_above(bool zero_allowed) {
  return CLI::Validator(
      [zero_allowed](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool number = !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
        if (number && (zero_allowed ? value >= 0 : value > 0)) return {};
        return "Value " + text + (zero_allowed ? " is not 0 or more" : " is not above 0");
      },
      zero_allowed ? "NONNEGATIVE" : "POSITIVE");
}

}  // namespace

Option& Option::positive() {
  option_->check(number_above(false));
  return *this;
}

Option& Option::non_negative() {
  option_->check(number_above(true));
  return *this;
}

Option& Option::one_of(std::vector<std::string> words) {
  option_->check(CLI::IsMember(std::move(words)));
  return *this;
}

Option& Option::check(Problem problem, std::string_view shown) {
  option_->check(CLI::Validator(
      [problem = std::move(problem)](std::string& value) { return problem(value); },
      std::string(shown)));
  return *this;
}

Option& Option::excludes(const Option& other) {
  option_->excludes(other.option_);
  return *this;
}

Option& Option::expected(int count) {
  option_->expected(count);
  return *this;
}

Option& Option::each(std::function<void(const std::string&)> seen) {
  option_->each([seen = std::move(seen)](const std::string& value) { seen(value); });
  return *this;
}

Option& Option::delimiter(char separator) {
  option_->delimiter(separator);
  return *this;
}

Option& Option::hidden() {
  option_->group("");  // CLI11's way: an option in the empty group is not shown
  return *this;
}

CommandLine::CommandLine(std::string tool, std::string description)
    : tool_(std::move(tool)), app_(std::make_unique<CLI::App>(std::move(description), tool_)) {
  // One style of --help: every option shows its default the same way, "--count INT=5".
  app_->option_defaults()->always_capture_default();
  app_->get_formatter()->column_width(36);
  app_->footer("Exit codes: 0 done (or stopped by SIGINT/SIGTERM), 1 failed at run time, "
              "2 wrong command line or config file.");
}

CommandLine::~CommandLine() = default;

Option CommandLine::add_stream(std::string_view name, std::string& value,
                               std::string_view help) {
  return Option(app_->add_option(std::string(name), value, std::string(help))
                    ->type_name("NAME")
                    ->check(stream_name_validator()));
}

Option CommandLine::add_streams(std::string_view name, std::vector<std::string>& values,
                                std::string_view help) {
  return Option(app_->add_option(std::string(name), values, std::string(help))
                    ->type_name("NAME")
                    ->check(stream_name_validator()));
}

template <class T>
Option CommandLine::add_option(std::string_view name, T& value, std::string_view help) {
  return Option(app_->add_option(std::string(name), value, std::string(help)));
}

// The value types the programs use (a new one: a line here).
template Option CommandLine::add_option(std::string_view, std::string&, std::string_view);
template Option CommandLine::add_option(std::string_view, int&, std::string_view);
template Option CommandLine::add_option(std::string_view, unsigned&, std::string_view);
template Option CommandLine::add_option(std::string_view, std::uint16_t&, std::string_view);
template Option CommandLine::add_option(std::string_view, std::int64_t&, std::string_view);
template Option CommandLine::add_option(std::string_view, std::uint64_t&, std::string_view);
template Option CommandLine::add_option(std::string_view, float&, std::string_view);
template Option CommandLine::add_option(std::string_view, double&, std::string_view);
template Option CommandLine::add_option(std::string_view, std::optional<int>&, std::string_view);
template Option CommandLine::add_option(std::string_view, std::optional<std::uint16_t>&,
                                        std::string_view);
template Option CommandLine::add_option(std::string_view, std::optional<double>&,
                                        std::string_view);
template Option CommandLine::add_option(std::string_view, std::vector<std::string>&,
                                        std::string_view);
template Option CommandLine::add_option(std::string_view, std::vector<int>&, std::string_view);

template <class T>
Option CommandLine::add_option_function(std::string_view name, std::function<void(const T&)> set,
                                        std::string_view help) {
  return Option(app_->add_option_function<T>(std::string(name), set, std::string(help)));
}

template Option CommandLine::add_option_function(std::string_view,
                                                 std::function<void(const float&)>,
                                                 std::string_view);

Option CommandLine::add_flag(std::string_view name, bool& value, std::string_view help,
                             std::string_view group) {
  auto* option = app_->add_flag(std::string(name), value, std::string(help));
  if (!group.empty()) option->group(std::string(group));
  return Option(option);
}

namespace {

// add_text and add_number: one option whose text `problem` checks, shown as `type_name`.
template <class T>
void add_checked(CLI::App& app, std::string_view name, T& value, std::string_view help,
                 std::string_view type_name, std::function<std::string(const std::string&)> problem,
                 std::string_view group) {
  auto* option =
      app.add_option(std::string(name), value, std::string(help))->type_name(std::string(type_name));
  if (problem) option->check(validator(std::move(problem), std::string(type_name)));
  if (!group.empty()) option->group(std::string(group));
}

}  // namespace

void CommandLine::add_text(std::string_view name, std::string& value, std::string_view help,
                           std::string_view type_name,
                           std::function<std::string(const std::string&)> problem,
                           std::string_view group) {
  add_checked(*app_, name, value, help, type_name, std::move(problem), group);
}

void CommandLine::add_number(std::string_view name, std::optional<double>& value,
                             std::string_view help, std::string_view type_name,
                             std::function<std::string(const std::string&)> problem,
                             std::string_view group) {
  add_checked(*app_, name, value, help, type_name, std::move(problem), group);
}

void CommandLine::add_config_file(std::vector<std::string> path_options) {
  for (std::string& name : path_options_) path_options.push_back(std::move(name));
  path_options_.clear();
  auto config = std::make_shared<YamlConfig>(std::move(path_options));
  config_ = config;
  app_->config_formatter(std::make_shared<CliYamlConfig>(config));
  app_->allow_config_extras(CLI::config_extras_mode::error);  // a typo in the file is an error
  app_->set_config("--config", "",
                  "YAML file of options (keys are the long option names; the command line "
                  "overrides the file)")
      ->type_name("FILE")
      // CLI11 checks the file name just before it reads the file: the moment to tell the reader
      // which folder relative paths in it start from.
      ->check(CLI::Validator(
          [config](std::string& path) {
            config->set_file(path);
            return std::string();
          },
          "", "config file"));
}

void CommandLine::add_path_option(std::string name) {
  if (config_) {
    config_->add_path_option(std::move(name));
  } else {
    path_options_.push_back(std::move(name));
  }
}

void CommandLine::add_placement(ThreadPlacement& placement) {
  app_->add_option("--cpu", placement.cpu, "pin the working thread to this CPU")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber);
  app_->add_option("--rt-priority", placement.rt_priority,
                  "run the working thread under SCHED_FIFO at this priority (needs root or "
                  "CAP_SYS_NICE)")
      ->type_name("1-99")
      ->check(CLI::Range(1, 99));
}

void CommandLine::add_trust(Trust& trust) {
  trust_ = &trust;
  app_->add_option("--trust-owner", trust_owner_,
                  "also accept streams owned by this user (name or uid); default: only your own")
      ->type_name("USER");
  app_->add_option("--trust-group", trust_group_,
                  "also accept streams owned by this group (name or gid): every member is then "
                  "trusted to be the writer")
      ->type_name("GROUP");
}

std::optional<int> CommandLine::parse(int argc, char** argv) {
  try {
    app_->parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app_->exit(e) == 0 ? kExitOk : kExitUsage;
  } catch (const CLI::CallForAllHelp& e) {
    return app_->exit(e) == 0 ? kExitOk : kExitUsage;
  } catch (const CLI::CallForVersion& e) {
    return app_->exit(e) == 0 ? kExitOk : kExitUsage;
  } catch (const CLI::ConfigError& e) {
    std::string what = as_sentence(e.what());
    // CLI11 calls every config file "INI"; say what the user gave.
    const std::string ini = "INI was not able to parse ";
    if (what.rfind(ini, 0) == 0) {
      what = "the config file has no option named '" + what.substr(ini.size()) + "'";
    }
    return usage_error(what + "; see --help for the option names");
  } catch (const CLI::ParseError& e) {
    return usage_error(as_sentence(e.what()) + "; see " + tool_ + " --help");
  }
  if (trust_ != nullptr && (!trust_owner_.empty() || !trust_group_.empty())) {
    auto trust = Trust::parse(trust_owner_, trust_group_);
    if (!trust) return usage_error(trust.error().message);
    *trust_ = *trust;
  }
  return std::nullopt;
}

std::vector<Option> CommandLine::parse_order() const {
  std::vector<Option> order;
  for (CLI::Option* option : app_->parse_order()) order.emplace_back(option);
  return order;
}

int CommandLine::fail(std::string_view message) const {
  std::fprintf(stderr, "%s: %.*s\n", tool_.c_str(), static_cast<int>(message.size()),
               message.data());
  return kExitFailure;
}

int CommandLine::usage_error(std::string_view message) const {
  std::fprintf(stderr, "%s: %.*s\n", tool_.c_str(), static_cast<int>(message.size()),
               message.data());
  return kExitUsage;
}

int CommandLine::fail(const Error& error) const {
  const bool usage =
      error.code == ErrorCode::invalid_name || error.code == ErrorCode::invalid_argument;
  return usage ? usage_error(error.message) : fail(std::string_view(error.message));
}

std::optional<int> CommandLine::apply_placement(const ThreadPlacement& placement) const {
  const auto placed = apply_thread_placement(placement);
  if (placed) return std::nullopt;
  const Error& error = placed.error();
  return error.code == ErrorCode::permission_denied ? fail(std::string_view(error.message))
                                                    : usage_error(error.message);
}

bool stderr_is_terminal() noexcept { return ::isatty(STDERR_FILENO) != 0; }

}  // namespace sim::apps
