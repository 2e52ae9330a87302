// SPDX-License-Identifier: Apache-2.0
// The one status line of every long-running program: on a terminal it is redrawn in place at
// most once a second ("\r" + clear); elsewhere (a log, a pipe) nothing is drawn until the final
// summary, which is one line "tool: …" unless --quiet. Its text is "name value" fields separated
// by two spaces: "frames 1200  rate 10.0 Hz  dropped 0".
#pragma once

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace sim::apps {

// "frames 1200  rate 10.0 Hz": fields in the order given.
std::string fields(std::initializer_list<std::pair<std::string_view, std::string>> items);
// A number with `decimals` digits after the point ("10.0").
std::string number(double value, int decimals = 1);
// A data rate in the unit that suits it: "22.4 MB/s", "3.1 kB/s", "12 B/s" (SI, as sensors quote).
std::string bandwidth(double bytes_per_s);

class StatusLine {
 public:
  // `live`: redraw in place (stderr is a terminal and the user did not ask for --quiet);
  // `quiet`: no summary either.
  StatusLine(std::string tool, bool live, bool quiet = false, std::FILE* out = stderr);
  // For the usual case: live when stderr is a terminal and not quiet.
  static StatusLine for_stderr(std::string tool, bool quiet);

  // Whether a redraw is due (live, and a second has passed since the last one).
  bool due() const noexcept;
  // Redraws the line with `text` when due.
  void update(std::string_view text);
  // A message of its own ("tool: camera unplugged") that does not break the live line.
  void note(std::string_view message);
  // The final line: "tool: text" (after clearing the live line), unless quiet.
  void finish(std::string_view text);

 private:
  std::string tool_;
  bool live_;
  bool quiet_;
  std::FILE* out_;
  bool drawn_ = false;
  std::int64_t last_draw_ns_ = 0;
};

}  // namespace sim::apps
