// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/status_line.hpp"

#include <unistd.h>

#include "sim/clock.hpp"

namespace sim::apps {
namespace {
constexpr std::int64_t kRedrawPeriodNs = 1'000'000'000;
constexpr const char* kClearLine = "\r\033[K";
}  // namespace

std::string fields(std::initializer_list<std::pair<std::string_view, std::string>> items) {
  std::string line;
  for (const auto& [name, value] : items) {
    if (!line.empty()) line += "  ";
    line += name;
    line += ' ';
    line += value;
  }
  return line;
}

std::string number(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

std::string bandwidth(double bytes_per_s) {
  if (bytes_per_s >= 1e6) return number(bytes_per_s / 1e6) + " MB/s";
  if (bytes_per_s >= 1e3) return number(bytes_per_s / 1e3) + " kB/s";
  return number(bytes_per_s, 0) + " B/s";
}

StatusLine::StatusLine(std::string tool, bool live, bool quiet, std::FILE* out)
    : tool_(std::move(tool)), live_(live && !quiet), quiet_(quiet), out_(out) {}

StatusLine StatusLine::for_stderr(std::string tool, bool quiet) {
  return StatusLine(std::move(tool), ::isatty(STDERR_FILENO) != 0, quiet);
}

bool StatusLine::due() const noexcept {
  return live_ && (last_draw_ns_ == 0 || monotonic_ns() - last_draw_ns_ >= kRedrawPeriodNs);
}

void StatusLine::update(std::string_view text) {
  if (!due()) return;
  last_draw_ns_ = monotonic_ns();
  std::fprintf(out_, "%s%.*s", kClearLine, static_cast<int>(text.size()), text.data());
  std::fflush(out_);
  drawn_ = true;
}

void StatusLine::note(std::string_view message) {
  std::fprintf(out_, "%s%s: %.*s\n", drawn_ ? kClearLine : "", tool_.c_str(),
               static_cast<int>(message.size()), message.data());
  std::fflush(out_);
  last_draw_ns_ = 0;  // redraw the live line at the next update
}

void StatusLine::finish(std::string_view text) {
  if (drawn_) std::fprintf(out_, "%s", kClearLine);
  drawn_ = false;
  if (!quiet_) {
    std::fprintf(out_, "%s: %.*s\n", tool_.c_str(), static_cast<int>(text.size()), text.data());
  }
  std::fflush(out_);
}

}  // namespace sim::apps
