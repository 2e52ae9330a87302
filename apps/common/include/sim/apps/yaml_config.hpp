// SPDX-License-Identifier: Apache-2.0
// Reads a YAML config file into option values, so a file and the command line are merged by one
// mechanism (CommandLine hands these entries to CLI11, which sets from the file only the options
// the command line left unset):
//   stream: /camera_front     -> --stream /camera_front
//   rt_priority: 20           -> --rt-priority 20   ('_' and '-' are the same in keys)
//   roi: [0, 0, 640, 480]     -> --roi 0 0 640 480
//   controls: {gain: 3}       -> --controls gain=3  (a map becomes "key=value" items, in order)
// Options named as paths take a relative file name relative to the config file's folder, so a
// file and the calibration beside it move together (a URL, "file:///…", is left as it is):
//   calibration: unit.csv     -> --calibration /etc/sim/hesai/unit.csv  (for /etc/sim/hesai/x.yaml)
// It knows nothing of CLI11: only command_line.cpp compiles the command-line parser.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "sim/result.hpp"

namespace sim::apps {

// One key of the file: the long option name ('_' as '-') and its values in order.
struct ConfigEntry {
  std::string name;
  std::vector<std::string> inputs;
};

class YamlConfig {
 public:
  // `path_options`: long option names ("calibration") whose values are file names.
  explicit YamlConfig(std::vector<std::string> path_options = {});

  // The file about to be read: its folder anchors relative paths.
  void set_file(const std::string& path);
  // One more option whose values are file names.
  void add_path_option(std::string name);

  // The file's options, in the file's order; an invalid_argument sentence for a file that is not
  // a YAML map of options.
  Expected<std::vector<ConfigEntry>> read(std::istream& input) const;

 private:
  std::vector<std::string> path_options_;  // with '-' for '_'
  std::string folder_;                     // of the file being read; empty: the working folder
};

}  // namespace sim::apps
