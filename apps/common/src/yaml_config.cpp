// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/yaml_config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <optional>

namespace sim::apps {
namespace {

std::string line_of(const YAML::Mark& mark) { return std::to_string(mark.line + 1); }

Error config_error(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// A list's or a map's element: a value, or nothing when it nests deeper.
std::optional<std::string> scalar(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  return node.Scalar();
}

Error too_deep(const YAML::Node& node, const std::string& key) {
  return config_error("the config file's '" + key + "' (line " + line_of(node.Mark()) +
                      ") nests too deep; give a value, a list or a map of values");
}

std::string dashed(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

// The values of one key, appended to `inputs`; one sentence when one of them nests deeper.
Expected<void> values_of(const YAML::Node& value, const std::string& key,
                         std::vector<std::string>& inputs) {
  if (value.IsMap()) {
    for (const auto& pair : value) {
      auto text = scalar(pair.second);
      if (!text) return too_deep(pair.second, key);
      inputs.push_back(pair.first.Scalar() + "=" + *text);
    }
  } else if (value.IsSequence()) {
    for (const auto& element : value) {
      auto text = scalar(element);
      if (!text) return too_deep(element, key);
      inputs.push_back(*text);
    }
  } else {
    inputs.push_back(value.Scalar());
  }
  return {};
}

}  // namespace

YamlConfig::YamlConfig(std::vector<std::string> path_options) {
  for (auto& name : path_options) path_options_.push_back(dashed(std::move(name)));
}

void YamlConfig::add_path_option(std::string name) { path_options_.push_back(dashed(std::move(name))); }

void YamlConfig::set_file(const std::string& path) {
  folder_ = std::filesystem::path(path).parent_path().string();
}

Expected<std::vector<ConfigEntry>> YamlConfig::read(std::istream& input) const {
  YAML::Node root;
  try {
    root = YAML::Load(input);
  } catch (const YAML::Exception& e) {
    return config_error("the config file is not valid YAML (" + e.msg + " at line " +
                        line_of(e.mark) + "); fix the file");
  }
  std::vector<ConfigEntry> result;
  if (root.IsNull()) return result;
  if (!root.IsMap()) return config_error("the config file must be a map of option: value");
  for (const auto& key_value : root) {
    ConfigEntry entry;
    entry.name = dashed(key_value.first.Scalar());
    const YAML::Node& value = key_value.second;
    if (!value.IsMap() && !value.IsSequence() && !value.IsScalar()) {
      continue;  // "key:" with no value leaves the option at its default
    }
    if (auto read_values = values_of(value, entry.name, entry.inputs); !read_values) {
      return read_values.error();
    }
    if (!folder_.empty() &&
        std::find(path_options_.begin(), path_options_.end(), entry.name) != path_options_.end()) {
      for (std::string& file : entry.inputs) {
        const bool url = file.find("://") != std::string::npos;
        if (!file.empty() && !url && std::filesystem::path(file).is_relative()) {
          file = (std::filesystem::path(folder_) / file).string();
        }
      }
    }
    result.push_back(std::move(entry));
  }
  return result;
}

}  // namespace sim::apps
