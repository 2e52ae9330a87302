// SPDX-License-Identifier: Apache-2.0
// CSV format: reference §1.2. Files come from users and from sensors, so every malformed line
// is reported with its number and what to do, and nothing past the text is ever read.
#include "sim/hesai/calibration.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace sim::hesai {
namespace {

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool parse_double(std::string_view s, double& out) noexcept {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc{} && end == s.data() + s.size() && std::isfinite(out);
}

bool parse_channel(std::string_view s, unsigned& out) noexcept {
  s = trim(s);
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc{} && end == s.data() + s.size();
}

// Splits "a,b,c" into at most N fields; returns the field count, or N+1 when there are more
// non-empty fields than N (trailing empty fields, as spreadsheets write them, are ignored).
template <std::size_t N>
std::size_t split(std::string_view line, std::array<std::string_view, N>& fields) noexcept {
  std::size_t count = 0;
  while (true) {
    const std::size_t comma = line.find(',');
    const std::string_view field = line.substr(0, comma);
    if (count < N) {
      fields[count] = field;
    } else if (!trim(field).empty()) {
      return N + 1;
    }
    ++count;
    if (comma == std::string_view::npos) break;
    line.remove_prefix(comma + 1);
  }
  return std::min(count, N);
}

std::string quote(std::string_view line) {
  constexpr std::size_t max_shown = 60;
  std::string shown;
  for (char c : line.substr(0, max_shown)) {
    shown += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  }
  if (line.size() > max_shown) shown += "...";
  return "'" + shown + "'";
}

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// Walks the lines of a CSV with an optional BOM, LF or CRLF, skipping blank lines, and hands
// each data line (after an optional non-numeric header line) to `row`, with its 1-based number.
template <typename Row>
std::optional<Error> for_each_row(std::string_view text, std::string_view source,
                                  std::string_view what, Row&& row) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::size_t line_number = 0;
  bool seen_first = false;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_number;
    if (line.find('\0') != std::string_view::npos) {
      return invalid(std::string(source) + ":" + std::to_string(line_number) +
                     ": contains a NUL byte, so this is not a text " + std::string(what) +
                     " file; pass the CSV file that came with the sensor");
    }
    if (trim(line).empty()) continue;
    if (!seen_first) {
      seen_first = true;
      // A header is any first line that does not start with a channel number
      // ("Laser id,Elevation,Azimuth", "Channel,fire time(us)").
      const std::string_view first = trim(line);
      if (!std::isdigit(static_cast<unsigned char>(first.front()))) continue;
    }
    if (auto error = row(trim(line), line_number)) return error;
  }
  return std::nullopt;
}

std::optional<std::string> read_file(const std::filesystem::path& path, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = "cannot open '" + path.string() + "'; check the path and its permissions";
    return std::nullopt;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    error = "cannot read '" + path.string() + "'";
    return std::nullopt;
  }
  return buffer.str();
}

// Every channel 1..N exactly once, N matching the model when one is given.
template <typename T>
std::optional<Error> check_channels(const std::vector<std::optional<T>>& rows,
                                    std::optional<Model> model, std::string_view source,
                                    std::string_view what) {
  if (rows.empty()) {
    return invalid(std::string(source) + " has no " + std::string(what) +
                   " lines; expected a header line and one line per channel");
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i]) {
      return invalid(std::string(source) + " has no line for channel " + std::to_string(i + 1) +
                     " but has channel " + std::to_string(rows.size()) +
                     "; every channel must appear once");
    }
  }
  if (model && rows.size() != info(*model).channels) {
    return invalid(std::string(source) + " has " + std::to_string(rows.size()) +
                   " channels but a " + std::string(to_string(*model)) + " has " +
                   std::to_string(info(*model).channels) +
                   "; use the file of this sensor or set the right model");
  }
  return std::nullopt;
}

constexpr unsigned max_channels = 128;

}  // namespace

Expected<Calibration> Calibration::parse(std::string_view text, std::optional<Model> model,
                                         std::string_view source) {
  std::vector<std::optional<ChannelAngles>> rows;
  auto error = for_each_row(
      text, source, "calibration",
      [&](std::string_view line, std::size_t number) -> std::optional<Error> {
        const std::string where = std::string(source) + ":" + std::to_string(number) + ": ";
        std::array<std::string_view, 3> f;
        const std::size_t n = split(line, f);
        unsigned channel = 0;
        double elevation = 0, azimuth = 0;
        if (n != 3 || !parse_channel(f[0], channel) || !parse_double(f[1], elevation) ||
            !parse_double(f[2], azimuth)) {
          return invalid(where + "expected 'channel,elevation,azimuth' (three numbers), got " +
                         quote(line) + "; fix the line or use the sensor's own file");
        }
        if (channel < 1 || channel > max_channels) {
          return invalid(where + "channel " + std::to_string(channel) +
                         " is out of range; channels count from 1 up to " +
                         std::to_string(max_channels));
        }
        if (std::abs(elevation) > 90.0 || std::abs(azimuth) > 180.0) {
          return invalid(where + "elevation must be within ±90° and azimuth offset within "
                                 "±180°, got " + quote(line) +
                         "; this is not an angle-correction file");
        }
        if (rows.size() < channel) rows.resize(channel);
        if (rows[channel - 1]) {
          return invalid(where + "channel " + std::to_string(channel) +
                         " appears twice; every channel must appear once");
        }
        rows[channel - 1] =
            ChannelAngles{static_cast<float>(elevation), static_cast<float>(azimuth)};
        return std::nullopt;
      });
  if (error) return *error;
  if (auto bad = check_channels(rows, model, source, "calibration")) return *bad;
  std::vector<ChannelAngles> angles;
  angles.reserve(rows.size());
  for (const auto& row : rows) angles.push_back(*row);
  return Calibration(std::move(angles));
}

Expected<Calibration> Calibration::load(const std::filesystem::path& path,
                                        std::optional<Model> model) {
  std::string error;
  auto text = read_file(path, error);
  if (!text) return invalid("calibration: " + error);
  return parse(*text, model, path.filename().string());
}

Expected<Calibration> Calibration::from_angles(std::vector<ChannelAngles> angles) {
  if (angles.empty() || angles.size() > max_channels) {
    return invalid("a calibration needs between 1 and " + std::to_string(max_channels) +
                   " channels");
  }
  return Calibration(std::move(angles));
}

Expected<FiretimeCorrection> FiretimeCorrection::parse(std::string_view text,
                                                       std::optional<Model> model,
                                                       std::string_view source) {
  std::vector<std::optional<double>> rows;
  auto error = for_each_row(
      text, source, "firing-time",
      [&](std::string_view line, std::size_t number) -> std::optional<Error> {
        const std::string where = std::string(source) + ":" + std::to_string(number) + ": ";
        std::array<std::string_view, 2> f;
        const std::size_t n = split(line, f);
        unsigned channel = 0;
        double us = 0;
        if (n != 2 || !parse_channel(f[0], channel) || !parse_double(f[1], us)) {
          return invalid(where + "expected 'channel,fire time in µs' (two numbers), got " +
                         quote(line) + "; fix the line or use Hesai's firing-time file");
        }
        if (channel < 1 || channel > max_channels) {
          return invalid(where + "channel " + std::to_string(channel) +
                         " is out of range; channels count from 1 up to " +
                         std::to_string(max_channels));
        }
        if (std::abs(us) > 1000.0) {
          return invalid(where + "a firing time of " + quote(f[1]) +
                         " µs is impossible (more than 1 ms); this is not a firing-time file");
        }
        if (rows.size() < channel) rows.resize(channel);
        if (rows[channel - 1]) {
          return invalid(where + "channel " + std::to_string(channel) +
                         " appears twice; every channel must appear once");
        }
        rows[channel - 1] = us;
        return std::nullopt;
      });
  if (error) return *error;
  if (auto bad = check_channels(rows, model, source, "firing-time")) return *bad;
  std::vector<double> us;
  us.reserve(rows.size());
  for (const auto& row : rows) us.push_back(*row);
  return FiretimeCorrection(std::move(us));
}

Expected<FiretimeCorrection> FiretimeCorrection::load(const std::filesystem::path& path,
                                                      std::optional<Model> model) {
  std::string error;
  auto text = read_file(path, error);
  if (!text) return invalid("firing-time correction: " + error);
  return parse(*text, model, path.filename().string());
}

}  // namespace sim::hesai
