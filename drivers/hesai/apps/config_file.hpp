// SPDX-License-Identifier: Apache-2.0
// The live driver's YAML configuration (config/hesai/*.yaml): the same settings as its
// command-line options, which override the file.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "sim/hesai/stream_options.hpp"

namespace sim::hesai {

struct NetworkOptions {
  std::string bind = "0.0.0.0";
  int port = 2368;                  // 0: an ephemeral port, printed at start (tests)
  std::string multicast_group;      // empty: unicast/broadcast
  std::string source;               // empty: accept packets from any sender
  int receive_buffer = 16 << 20;    // bytes asked for SO_RCVBUF
  double status_interval_s = -1;    // <0: 1 s on a terminal, 10 s otherwise; 0: never
  double silence_timeout_s = 0.5;   // a longer gap means the sensor stopped: restart the frame
};

// Loads `path` into the options. Relative file names in it (calibration, firetimes) are taken
// relative to the file's folder. Unknown keys are an error, so a typo is not silently ignored.
std::optional<Error> load_config_file(const std::filesystem::path& path, StreamOptions& stream,
                                      NetworkOptions& network);

}  // namespace sim::hesai
