// SPDX-License-Identifier: Apache-2.0
#include "bridge_options.hpp"

#include <algorithm>
#include <charconv>
#include <map>

#include "sim/names.hpp"

namespace sim::bridge {

namespace {

Error usage(std::string sentence) { return Error{ErrorCode::invalid_argument, std::move(sentence)}; }

// "/stream=value" items of one option into a map; an error names the option and the item.
Expected<std::map<std::string, std::string>> per_stream(const std::vector<std::string>& items,
                                                        const char* option,
                                                        const std::vector<std::string>& publish) {
  std::map<std::string, std::string> out;
  for (const std::string& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size()) {
      return usage(std::string(option) + " '" + item + "' is not STREAM=VALUE, e.g. " + option +
                   " /lidar_top=…");
    }
    const std::string stream = item.substr(0, eq);
    if (std::find(publish.begin(), publish.end(), stream) == publish.end()) {
      return usage(std::string(option) + " names " + stream + ", which is not given to --publish");
    }
    out[stream] = item.substr(eq + 1);
  }
  return out;
}

bool parse_double(const std::string& text, double& value) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

// A ROS topic name: a slash, then letters, digits, '_' and '/' (no "//", no trailing '/').
bool valid_topic(const std::string& name) {
  if (name.size() < 2 || name.front() != '/' || name.back() == '/') return false;
  for (std::size_t i = 1; i < name.size(); ++i) {
    const char c = name[i];
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || (c == '/' && name[i - 1] != '/');
    if (!ok) return false;
  }
  return true;
}

}  // namespace

Expected<BridgePlan> plan_bridge(const RawOptions& raw) {
  if (raw.publish.empty() && raw.subscribe.empty()) {
    return usage("nothing to bridge; give --publish /stream and/or --subscribe /topic");
  }
  QosChoice qos;
  qos.reliable = raw.reliable;

  auto frame_ids = per_stream(raw.frame_id, "--frame-id", raw.publish);
  if (!frame_ids) return frame_ids.error();
  auto rates = per_stream(raw.max_rate, "--max-rate", raw.publish);
  if (!rates) return rates.error();
  auto compress = per_stream(raw.compress, "--compress", raw.publish);
  if (!compress) return compress.error();

  BridgePlan plan;
  for (const std::string& stream : raw.publish) {
    if (auto problem = stream_name_problem(stream); !problem.empty()) return usage(problem);
    OutboundOptions o;
    o.stream = stream;
    o.qos = qos;
    if (auto it = frame_ids->find(stream); it != frame_ids->end()) o.frame_id = it->second;
    if (auto it = rates->find(stream); it != rates->end()) {
      if (!parse_double(it->second, o.max_rate_hz) || !(o.max_rate_hz > 0)) {
        return usage("--max-rate " + stream + "=" + it->second + " is not a positive rate in Hz");
      }
    }
    if (auto it = compress->find(stream); it != compress->end()) {
      const std::string& v = it->second;
      int quality = 90;
      if (v.rfind("jpeg", 0) != 0 || (v.size() > 4 && v[4] != ':')) {
        return usage("--compress " + stream + "=" + v + " is not jpeg or jpeg:QUALITY");
      }
      if (v.size() > 4) {
        double q = 0;
        if (!parse_double(v.substr(5), q) || q < 1 || q > 100 || q != static_cast<int>(q)) {
          return usage("--compress " + stream + "=" + v + ": the JPEG quality must be 1-100");
        }
        quality = static_cast<int>(q);
      }
      o.jpeg_quality = quality;
    }
    plan.outbound.push_back(std::move(o));
  }

  std::map<std::string, std::string> explicit_as;
  std::vector<std::string> plain_as(raw.subscribe.size());
  std::size_t plain_index = 0;
  for (const std::string& item : raw.as) {
    const auto eq = item.find('=');
    if (eq != std::string::npos) {
      explicit_as[item.substr(0, eq)] = item.substr(eq + 1);
      continue;
    }
    const std::size_t after = plain_index < raw.as_after.size() ? raw.as_after[plain_index] : 0;
    ++plain_index;
    if (after == 0 || after > raw.subscribe.size() || !plain_as[after - 1].empty()) {
      return usage("--as " + item + " must follow the --subscribe it renames");
    }
    plain_as[after - 1] = item;
  }
  for (std::size_t i = 0; i < raw.subscribe.size(); ++i) {
    const std::string& topic = raw.subscribe[i];
    if (!valid_topic(topic)) {
      return usage("--subscribe " + topic + " is not a ROS topic name such as /camera_remote");
    }
    InboundOptions in;
    in.topic = topic;
    in.qos = qos;
    in.stream = plain_as[i];
    if (auto it = explicit_as.find(topic); it != explicit_as.end()) in.stream = it->second;
    if (in.stream.empty()) in.stream = topic;
    if (auto problem = stream_name_problem(in.stream); !problem.empty()) {
      return usage("--subscribe " + topic + " needs a SIM stream name: " + problem +
                   " (give one with --as /name)");
    }
    plan.inbound.push_back(std::move(in));
  }
  return plan;
}

}  // namespace sim::bridge
