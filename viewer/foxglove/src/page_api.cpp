// SPDX-License-Identifier: Apache-2.0
#include "page_api.hpp"

#include <nlohmann/json.hpp>

#include "projection.hpp"

namespace sim::foxglove {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<std::string> percent_decode(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '+') {
      out += ' ';
    } else if (c == '%') {
      if (i + 2 >= text.size()) return std::nullopt;
      const int hi = hex_value(text[i + 1]);
      const int lo = hex_value(text[i + 2]);
      if (hi < 0 || lo < 0) return std::nullopt;
      out += static_cast<char>(hi * 16 + lo);
      i += 2;
    } else {
      out += c;
    }
  }
  return out;
}

const char* kind_name(LayoutKind kind) {
  switch (kind) {
    case LayoutKind::image: return "image";
    case LayoutKind::points: return "points";
    case LayoutKind::bytes: return "bytes";
  }
  return "bytes";
}

}  // namespace

std::optional<Target> parse_target(std::string_view target) {
  if (target.empty() || target.front() != '/' || target.size() > 4096) return std::nullopt;
  Target out;
  const auto question = target.find('?');
  auto path = percent_decode(target.substr(0, question));
  if (!path) return std::nullopt;
  out.path = std::move(*path);
  if (question == std::string_view::npos) return out;
  std::string_view query = target.substr(question + 1);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    if (pair.empty()) continue;
    const auto eq = pair.find('=');
    auto key = percent_decode(pair.substr(0, eq));
    auto value = percent_decode(eq == std::string_view::npos ? std::string_view{}
                                                             : pair.substr(eq + 1));
    if (!key || !value) return std::nullopt;
    out.query[std::move(*key)] = std::move(*value);
  }
  return out;
}

namespace {

void add_sensor(nlohmann::json& s, const StreamEntry& e, const std::vector<StreamEntry>& streams,
                const std::vector<FrameTransform>& mountings) {
  const StreamStatus& st = *e.status;
  if (!st.sensor_problem.empty()) s["sensor_problem"] = st.sensor_problem;
  else if (!e.mounting_problem.empty()) s["sensor_problem"] = e.mounting_problem;
  const std::optional<SensorInfo>& sensor = st.sensor;
  s["frame_id"] = frame_of(e.name, sensor);
  if (!sensor) return;
  s["parent_frame"] = sensor->parent_frame;
  s["mounted"] = sensor->mounting.has_value();
  if (!sensor->calibration || st.layout.kind != LayoutKind::image) return;
  s["calibration"] = summary(*sensor->calibration);
  if (e.calibration_channel) s["calibration_topic"] = e.calibration_channel->topic;
  auto partners = nlohmann::json::array();
  for (const StreamEntry& other : streams) {
    if (!other.status || other.status->layout.kind != LayoutKind::points) continue;
    if (pose_between(mountings, frame_of(other.name, other.status->sensor), s["frame_id"].get<std::string>())) {
      partners.push_back(other.name);
    }
  }
  s["projectable"] = std::move(partners);
}

}  // namespace

std::string streams_json(const std::vector<StreamEntry>& streams,
                         const std::vector<FrameTransform>& mountings) {
  using nlohmann::json;
  json list = json::array();
  for (const StreamEntry& e : streams) {
    json s = {{"name", e.name}};
    if (!e.status) {
      s["kind"] = "unknown";
      s["problem"] = e.problem;
      list.push_back(std::move(s));
      continue;
    }
    const StreamStatus& st = *e.status;
    s["kind"] = kind_name(st.layout.kind);
    s["layout"] = st.layout.describe();
    s["capacity"] = st.capacity;
    s["frames"] = st.frames_published;
    s["rate_hz"] = e.rate_hz;
    s["age_ms"] = e.age_ns < 0 ? json(nullptr) : json(static_cast<double>(e.age_ns) / 1e6);
    s["writer_alive"] = st.writer_alive;
    s["writer_pid"] = st.writer_pid;
    s["writer"] = st.writer_command;
    if (st.layout.kind == LayoutKind::image) {
      s["width"] = st.layout.image.width;
      s["height"] = st.layout.image.height;
      s["format"] = to_string(st.layout.image.format);
    }
    if (e.channel) {
      s["channel_id"] = e.channel->id;
      s["topic"] = e.channel->topic;
      s["schema"] = e.channel->schema_name;
    }
    add_sensor(s, e, streams, mountings);
    if (st.clock) {
      s["clock"] = {{"summary", summary(*st.clock)},
                    {"verdict", to_string(st.clock->verdict)},
                    {"problem", st.clock->problem}};
    }
    list.push_back(std::move(s));
  }
  return list.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace sim::foxglove
