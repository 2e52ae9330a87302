// SPDX-License-Identifier: Apache-2.0
#include "config_file.hpp"

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>

namespace sim::hesai {
namespace {

Error config_error(const std::filesystem::path& path, const std::string& what) {
  return Error{ErrorCode::invalid_argument, path.string() + ": " + what};
}

}  // namespace

std::optional<Error> load_config_file(const std::filesystem::path& path, StreamOptions& s,
                                      NetworkOptions& n) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::BadFile&) {
    return Error{ErrorCode::not_found, "cannot read the config file " + path.string() +
                                           "; check the path given to --config."};
  } catch (const YAML::Exception& e) {
    return config_error(path, "not valid YAML (" + e.msg + " at line " +
                                  std::to_string(e.mark.line + 1) + "); fix the file.");
  }
  if (!root.IsMap()) return config_error(path, "expected a map of settings (key: value lines).");
  const std::filesystem::path folder = path.parent_path();
  auto file_path = [&](const std::string& value) {
    const std::filesystem::path p(value);
    return p.is_absolute() || folder.empty() ? p : folder / p;
  };

  using Setter = std::function<void(const YAML::Node&)>;
  const std::map<std::string, Setter> setters = {
      {"stream", [&](const YAML::Node& v) { s.config.stream = v.as<std::string>(); }},
      {"model",
       [&](const YAML::Node& v) {
         const auto text = v.as<std::string>();
         if (text == "auto") {
           s.model.reset();
           return;
         }
         const auto model = parse_model(text);
         if (!model) throw std::invalid_argument("unknown model '" + text + "'; use one of " + std::string(model_names()));
         s.model = *model;
       }},
      {"calibration", [&](const YAML::Node& v) { s.config.calibration = file_path(v.as<std::string>()); }},
      {"firetimes", [&](const YAML::Node& v) { s.config.firetimes = file_path(v.as<std::string>()); }},
      {"cut_azimuth", [&](const YAML::Node& v) { s.config.assembler.cut_azimuth_deg = v.as<double>(); }},
      {"min_range", [&](const YAML::Node& v) { s.config.assembler.min_range_m = v.as<float>(); }},
      {"max_range", [&](const YAML::Node& v) { s.config.assembler.max_range_m = v.as<float>(); }},
      {"keep_zero_distance", [&](const YAML::Node& v) { s.config.assembler.drop_zero_distance = !v.as<bool>(); }},
      {"keep_identical_returns", [&](const YAML::Node& v) { s.config.assembler.drop_identical_returns = !v.as<bool>(); }},
      {"dual_return_threshold", [&](const YAML::Node& v) { s.config.assembler.multi_return_distance_threshold_m = v.as<float>(); }},
      {"partial_frames", [&](const YAML::Node& v) { s.config.assembler.emit_partial_frames = v.as<bool>(); }},
      {"firetime_azimuth_compensation", [&](const YAML::Node& v) { s.config.assembler.firetime_azimuth_compensation = v.as<bool>(); }},
      {"returns", [&](const YAML::Node& v) { s.config.returns = v.as<unsigned>(); }},
      {"min_rpm", [&](const YAML::Node& v) { s.config.min_rpm = v.as<unsigned>(); }},
      {"checksum", [&](const YAML::Node& v) { s.config.checksum = v.as<bool>(); }},
      {"lock_memory", [&](const YAML::Node& v) { s.config.lock_memory = v.as<bool>(); }},
      {"cpu", [&](const YAML::Node& v) { s.cpu = v.as<int>(); }},
      {"rt_priority", [&](const YAML::Node& v) { s.rt_priority = v.as<int>(); }},
      {"bind", [&](const YAML::Node& v) { n.bind = v.as<std::string>(); }},
      {"port", [&](const YAML::Node& v) { n.port = v.as<int>(); }},
      {"multicast_group", [&](const YAML::Node& v) { n.multicast_group = v.as<std::string>(); }},
      {"source", [&](const YAML::Node& v) { n.source = v.as<std::string>(); }},
      {"receive_buffer", [&](const YAML::Node& v) { n.receive_buffer = v.as<int>(); }},
      {"status_interval", [&](const YAML::Node& v) { n.status_interval_s = v.as<double>(); }},
      {"silence_timeout", [&](const YAML::Node& v) { n.silence_timeout_s = v.as<double>(); }},
  };

  for (const auto& entry : root) {
    const auto key = entry.first.as<std::string>();
    const auto setter = setters.find(key);
    if (setter == setters.end()) {
      std::string known;
      for (const auto& [name, unused] : setters) known += (known.empty() ? "" : ", ") + name;
      return config_error(path, "unknown setting '" + key + "' at line " +
                                    std::to_string(entry.first.Mark().line + 1) +
                                    "; the settings are: " + known + ".");
    }
    if (entry.second.IsNull()) continue;  // "firetimes:" left empty: keep the default
    try {
      setter->second(entry.second);
    } catch (const std::exception& e) {
      return config_error(path, "the value of '" + key + "' at line " +
                                    std::to_string(entry.second.Mark().line + 1) +
                                    " is not valid (" + e.what() + ").");
    }
  }
  if (n.port < 0 || n.port > 65535) return config_error(path, "port must be 0–65535.");
  if (s.config.returns < 1 || s.config.returns > 3) return config_error(path, "returns must be 1, 2 or 3.");
  return std::nullopt;
}

}  // namespace sim::hesai
