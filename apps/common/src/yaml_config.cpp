// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/yaml_config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>

namespace sim::apps {
namespace {

std::string line_of(const YAML::Mark& mark) { return std::to_string(mark.line + 1); }

std::string scalar(const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar()) {
    throw CLI::ConfigError("the config file's '" + key + "' (line " + line_of(node.Mark()) +
                           ") nests too deep; give a value, a list or a map of values");
  }
  return node.Scalar();
}

std::string dashed(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

}  // namespace

YamlConfig::YamlConfig(std::vector<std::string> path_options) {
  for (auto& name : path_options) path_options_.push_back(dashed(std::move(name)));
}

void YamlConfig::add_path_option(std::string name) { path_options_.push_back(dashed(std::move(name))); }

void YamlConfig::set_file(const std::string& path) {
  folder_ = std::filesystem::path(path).parent_path().string();
}

std::vector<CLI::ConfigItem> YamlConfig::from_config(std::istream& input) const {
  YAML::Node root;
  try {
    root = YAML::Load(input);
  } catch (const YAML::Exception& e) {
    throw CLI::ConfigError("the config file is not valid YAML (" + e.msg + " at line " +
                           line_of(e.mark) + "); fix the file");
  }
  std::vector<CLI::ConfigItem> result;
  if (root.IsNull()) return result;
  if (!root.IsMap()) throw CLI::ConfigError("the config file must be a map of option: value");
  for (const auto& entry : root) {
    CLI::ConfigItem item;
    item.name = dashed(entry.first.Scalar());
    const YAML::Node& value = entry.second;
    if (value.IsMap()) {
      for (const auto& pair : value) {
        item.inputs.push_back(pair.first.Scalar() + "=" + scalar(pair.second, item.name));
      }
    } else if (value.IsSequence()) {
      for (const auto& element : value) item.inputs.push_back(scalar(element, item.name));
    } else if (value.IsScalar()) {
      item.inputs.push_back(value.Scalar());
    } else {
      continue;  // "key:" with no value leaves the option at its default
    }
    if (!folder_.empty() &&
        std::find(path_options_.begin(), path_options_.end(), item.name) != path_options_.end()) {
      for (std::string& file : item.inputs) {
        const bool url = file.find("://") != std::string::npos;
        if (!file.empty() && !url && std::filesystem::path(file).is_relative()) {
          file = (std::filesystem::path(folder_) / file).string();
        }
      }
    }
    result.push_back(std::move(item));
  }
  return result;
}

}  // namespace sim::apps
