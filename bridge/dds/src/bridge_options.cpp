// SPDX-License-Identifier: Apache-2.0
#include "bridge_options.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <set>

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
    if (!out.emplace(stream, item.substr(eq + 1)).second) {
      return usage(std::string(option) + " gives " + stream + " twice; give each stream once");
    }
  }
  return out;
}

// The first name given twice in `names`, if any.
std::optional<std::string> repeated(const std::vector<std::string>& names) {
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (!seen.insert(name).second) return name;
  }
  return std::nullopt;
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

namespace {

// Lowest --max-rate: one frame in 1000 s (a longer period would not fit the rate limiter).
constexpr double min_rate_hz = 1e-3;

Expected<OutboundOptions> outbound_for(const std::string& stream, const QosChoice& qos,
                                       const std::map<std::string, std::string>& frame_ids,
                                       const std::map<std::string, std::string>& rates,
                                       const std::map<std::string, std::string>& compress) {
  if (auto problem = stream_name_problem(stream); !problem.empty()) return usage(problem);
  OutboundOptions o;
  o.stream = stream;
  o.qos = qos;
  if (auto it = frame_ids.find(stream); it != frame_ids.end()) o.frame_id = it->second;
  if (auto it = rates.find(stream); it != rates.end()) {
    if (!parse_double(it->second, o.max_rate_hz) || !std::isfinite(o.max_rate_hz) ||
        !(o.max_rate_hz >= min_rate_hz)) {
      return usage("--max-rate " + stream + "=" + it->second +
                   " is not a rate in Hz from 0.001 up (a finite number)");
    }
  }
  if (auto it = compress.find(stream); it != compress.end()) {
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
  return o;
}

// Each --subscribe's SIM stream: a plain --as after it, TOPIC=STREAM, or the topic's name.
Expected<std::vector<std::string>> inbound_streams(const RawOptions& raw) {
  std::map<std::string, std::string> explicit_as;
  std::vector<std::string> streams(raw.subscribe.size());
  std::size_t plain_index = 0;
  for (const std::string& item : raw.as) {
    const auto eq = item.find('=');
    if (eq != std::string::npos) {
      const std::string topic = item.substr(0, eq);
      if (std::find(raw.subscribe.begin(), raw.subscribe.end(), topic) == raw.subscribe.end()) {
        return usage("--as " + item + " names " + topic + ", which is not given to --subscribe");
      }
      if (!explicit_as.emplace(topic, item.substr(eq + 1)).second) {
        return usage("--as gives " + topic + " twice; give each topic one stream");
      }
      continue;
    }
    const std::size_t after = plain_index < raw.as_after.size() ? raw.as_after[plain_index] : 0;
    ++plain_index;
    if (after == 0 || after > raw.subscribe.size() || !streams[after - 1].empty()) {
      return usage("--as " + item + " must follow the --subscribe it renames");
    }
    streams[after - 1] = item;
  }
  for (std::size_t i = 0; i < raw.subscribe.size(); ++i) {
    if (auto it = explicit_as.find(raw.subscribe[i]); it != explicit_as.end()) {
      if (!streams[i].empty()) return usage("--as gives " + raw.subscribe[i] + " twice; give it once");
      streams[i] = it->second;
    }
    if (streams[i].empty()) streams[i] = raw.subscribe[i];
  }
  return streams;
}

// Review H1: a name on both sides would bridge the bridge's own frames back into itself.
std::optional<Error> loop_problem(const BridgePlan& plan) {
  for (const InboundOptions& in : plan.inbound) {
    for (const OutboundOptions& out : plan.outbound) {
      const bool same_stream = in.stream == out.stream;
      const auto topics = published_topics(out);
      const bool same_topic = std::find(topics.begin(), topics.end(), in.topic) != topics.end();
      if (same_stream || same_topic) {
        return usage(std::string(same_stream ? "the SIM stream " + in.stream
                                             : "the ROS topic " + in.topic) +
                     " is both published (--publish " + out.stream + ") and subscribed (--subscribe " +
                     in.topic + "), which would feed the bridge's own messages back to it; bridge "
                     "each name in one direction");
      }
    }
  }
  return std::nullopt;
}

}  // namespace

Expected<BridgePlan> plan_bridge(const RawOptions& raw) {
  if (raw.publish.empty() && raw.subscribe.empty()) {
    return usage("nothing to bridge; give --publish /stream and/or --subscribe /topic");
  }
  if (auto name = repeated(raw.publish)) return usage("--publish " + *name + " is given twice; give it once");
  if (auto name = repeated(raw.subscribe)) return usage("--subscribe " + *name + " is given twice; give it once");
  auto frame_ids = per_stream(raw.frame_id, "--frame-id", raw.publish);
  if (!frame_ids) return frame_ids.error();
  auto rates = per_stream(raw.max_rate, "--max-rate", raw.publish);
  if (!rates) return rates.error();
  auto compress = per_stream(raw.compress, "--compress", raw.publish);
  if (!compress) return compress.error();

  BridgePlan plan;
  const QosChoice publish_qos{.reliable = raw.reliable};
  for (const std::string& stream : raw.publish) {
    auto o = outbound_for(stream, publish_qos, *frame_ids, *rates, *compress);
    if (!o) return o.error();
    plan.outbound.push_back(std::move(o.value()));
  }
  auto streams = inbound_streams(raw);
  if (!streams) return streams.error();
  if (auto stream = repeated(*streams)) {
    return usage("two --subscribe topics write into the SIM stream " + *stream +
                 ", which has one writer; give each its own stream with --as");
  }
  const QosChoice subscribe_qos{.reliable = raw.reliable_subscribe};
  for (std::size_t i = 0; i < raw.subscribe.size(); ++i) {
    const std::string& topic = raw.subscribe[i];
    if (!valid_topic(topic)) {
      return usage("--subscribe " + topic + " is not a ROS topic name such as /camera_remote");
    }
    InboundOptions in;
    in.topic = topic;
    in.qos = subscribe_qos;
    in.stream = (*streams)[i];
    if (auto problem = stream_name_problem(in.stream); !problem.empty()) {
      return usage("--subscribe " + topic + " needs a SIM stream name: " + problem +
                   " (give one with --as /name)");
    }
    plan.inbound.push_back(std::move(in));
  }
  if (auto loop = loop_problem(plan)) return *loop;
  return plan;
}

}  // namespace sim::bridge
