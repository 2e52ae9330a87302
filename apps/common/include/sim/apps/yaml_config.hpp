// SPDX-License-Identifier: Apache-2.0
// Reads a YAML config file into CLI11's option values, so a file and the command line are merged
// by one mechanism: CLI11 sets from the file only the options the command line left unset.
//   stream: /camera_front     -> --stream /camera_front
//   rt_priority: 20           -> --rt-priority 20   ('_' and '-' are the same in keys)
//   roi: [0, 0, 640, 480]     -> --roi 0 0 640 480
//   controls: {gain: 3}       -> --controls gain=3  (a map becomes "key=value" items, in order)
// Options named as paths take a relative file name relative to the config file's folder, so a
// file and the calibration beside it move together (a URL, "file:///…", is left as it is):
//   calibration: unit.csv     -> --calibration /etc/sim/hesai/unit.csv  (for /etc/sim/hesai/x.yaml)
#pragma once

#include <CLI/CLI.hpp>

#include <istream>
#include <string>
#include <vector>

namespace sim::apps {

class YamlConfig final : public CLI::Config {
 public:
  // `path_options`: long option names ("calibration") whose values are file names.
  explicit YamlConfig(std::vector<std::string> path_options = {});

  // The file about to be read: its folder anchors relative paths. (CLI::Config::from_file is not
  // virtual in CLI11 2.1, so CommandLine tells the folder when it checks the --config value.)
  void set_file(const std::string& path);
  // One more option whose values are file names.
  void add_path_option(std::string name);

  // Writing a config file back (--write-config) is not offered.
  std::string to_config(const CLI::App*, bool, bool, std::string) const override { return {}; }
  // Throws CLI::ConfigError with one sentence for a file that is not a YAML map of options.
  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override;

 private:
  std::vector<std::string> path_options_;  // with '-' for '_'
  std::string folder_;                     // of the file being read; empty: the working folder
};

}  // namespace sim::apps
