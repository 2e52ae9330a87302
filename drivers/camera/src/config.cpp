// SPDX-License-Identifier: Apache-2.0
#include "sim/camera/config.hpp"

#include <yaml-cpp/yaml.h>

#include <set>

namespace sim::camera {

namespace {

Error bad(const std::string& path, const std::string& what) {
  return Error{ErrorCode::invalid_argument, path + ": " + what};
}

}  // namespace

std::optional<Error> load_v4l2_config(const std::string& path, V4l2CaptureConfig& config,
                                      Placement& placement) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return Error{ErrorCode::not_found, "cannot read config file " + path + ": check the path"};
  } catch (const YAML::Exception& e) {
    return bad(path, "not valid YAML (" + e.msg + " at line " + std::to_string(e.mark.line + 1) +
                         "); fix the file");
  }
  if (root.IsNull()) return std::nullopt;
  if (!root.IsMap()) return bad(path, "the file must be a map of option: value");

  static const std::set<std::string> known = {
      "device", "stream", "format", "width", "height", "fps", "output", "buffers", "timestamps",
      "time_offset_ns", "controls", "cpu", "rt_priority", "checksum", "retry_period_ms",
      "frame_timeout_ms"};
  std::string key;
  try {
    for (const auto& item : root) {
      key = item.first.as<std::string>();
      if (known.count(key) == 0) return bad(path, "unknown key '" + key + "'; see docs/camera.md");
      const YAML::Node& value = item.second;
      if (key == "device") {
        config.device = value.as<std::string>();
      } else if (key == "stream") {
        config.stream = value.as<std::string>();
      } else if (key == "format") {
        const auto text = value.as<std::string>();
        if (text == "auto") {
          config.format.fourcc.reset();
        } else if (auto fourcc = FourCc::parse(text)) {
          config.format.fourcc = fourcc;
        } else {
          return bad(path, "format '" + text + "' is not auto or a four-letter code");
        }
      } else if (key == "width") {
        config.format.width = value.as<std::uint32_t>();
      } else if (key == "height") {
        config.format.height = value.as<std::uint32_t>();
      } else if (key == "fps") {
        config.format.fps = value.as<double>();
      } else if (key == "output") {
        const auto output = parse_output_format(value.as<std::string>());
        if (!output) return bad(path, "output must be bgr8, rgb8, mono8 or raw");
        config.format.output = *output;
      } else if (key == "buffers") {
        config.buffers = value.as<std::uint32_t>();
      } else if (key == "timestamps") {
        const auto text = value.as<std::string>();
        if (text != "device" && text != "receive") {
          return bad(path, "timestamps must be device or receive");
        }
        config.timestamps = text == "device" ? TimestampSource::device : TimestampSource::receive;
      } else if (key == "time_offset_ns") {
        config.time_offset_ns = value.as<std::int64_t>();
      } else if (key == "checksum") {
        config.checksum = value.as<bool>();
      } else if (key == "retry_period_ms") {
        config.retry_period = std::chrono::milliseconds(value.as<std::uint32_t>());
      } else if (key == "frame_timeout_ms") {
        config.frame_timeout = std::chrono::milliseconds(value.as<std::uint32_t>());
      } else if (key == "cpu") {
        placement.cpu = value.as<int>();
      } else if (key == "rt_priority") {
        placement.rt_priority = value.as<int>();
      } else if (key == "controls") {
        if (!value.IsMap()) return bad(path, "controls must be a map of name: value");
        for (const auto& control : value) {
          config.controls.push_back(
              {control.first.as<std::string>(), control.second.as<std::string>()});
        }
      }
    }
  } catch (const YAML::Exception& e) {
    return bad(path, "the value of '" + key + "' has the wrong type (line " +
                         std::to_string(e.mark.line + 1) + ")");
  }
  return std::nullopt;
}

std::optional<Error> load_aravis_config(const std::string& path, AravisCaptureConfig& config,
                                        Placement& placement) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return Error{ErrorCode::not_found, "cannot read config file " + path + ": check the path"};
  } catch (const YAML::Exception& e) {
    return bad(path, "not valid YAML (" + e.msg + " at line " + std::to_string(e.mark.line + 1) +
                         "); fix the file");
  }
  if (root.IsNull()) return std::nullopt;
  if (!root.IsMap()) return bad(path, "the file must be a map of option: value");
  static const std::set<std::string> known = {
      "device", "stream", "pixel_format", "output", "fps", "exposure_us", "gain", "roi",
      "packet_size", "packet_socket", "buffers", "device_timestamps", "checksum", "features",
      "cpu", "rt_priority", "retry_period_ms"};
  std::string key;
  try {
    for (const auto& item : root) {
      key = item.first.as<std::string>();
      if (known.count(key) == 0) return bad(path, "unknown key '" + key + "'; see docs/camera.md");
      const YAML::Node& value = item.second;
      if (key == "device") {
        config.device_id = value.as<std::string>();
      } else if (key == "stream") {
        config.stream = value.as<std::string>();
      } else if (key == "pixel_format") {
        config.pixel_format = value.as<std::string>();
      } else if (key == "output") {
        const auto output = parse_output_format(value.as<std::string>());
        if (!output) return bad(path, "output must be bgr8, rgb8, mono8 or raw");
        config.output = *output;
      } else if (key == "fps") {
        config.fps = value.as<double>();
      } else if (key == "exposure_us") {
        config.exposure_us = value.as<double>();
      } else if (key == "gain") {
        config.gain = value.as<double>();
      } else if (key == "roi") {
        const auto roi = value.as<std::vector<std::int32_t>>();
        if (roi.size() != 4) return bad(path, "roi must be [x, y, width, height]");
        config.offset_x = roi[0];
        config.offset_y = roi[1];
        config.width = roi[2];
        config.height = roi[3];
      } else if (key == "packet_size") {
        config.packet_size = value.as<std::int32_t>();
      } else if (key == "packet_socket") {
        config.packet_socket = value.as<bool>();
      } else if (key == "buffers") {
        config.buffers = value.as<std::uint32_t>();
      } else if (key == "device_timestamps") {
        config.device_timestamps = value.as<bool>();
      } else if (key == "checksum") {
        config.checksum = value.as<bool>();
      } else if (key == "retry_period_ms") {
        config.retry_period = std::chrono::milliseconds(value.as<std::uint32_t>());
      } else if (key == "cpu") {
        placement.cpu = value.as<int>();
      } else if (key == "rt_priority") {
        placement.rt_priority = value.as<int>();
      } else if (key == "features") {
        if (!value.IsMap()) return bad(path, "features must be a map of GenICam name: value");
        for (const auto& feature : value) {
          config.features.emplace_back(feature.first.as<std::string>(),
                                       feature.second.as<std::string>());
        }
      }
    }
  } catch (const YAML::Exception& e) {
    return bad(path, "the value of '" + key + "' has the wrong type (line " +
                         std::to_string(e.mark.line + 1) + ")");
  }
  return std::nullopt;
}

}  // namespace sim::camera
