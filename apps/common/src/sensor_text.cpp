// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/sensor_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace sim::apps {
namespace {

// Short decimals for people ("1.5", "-1.571"), exact ones for scripts.
std::string short_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", std::abs(value) < 5e-5 ? 0.0 : value);
  return text;
}

std::string exact_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

template <typename Numbers>
std::string json_array(const Numbers& numbers) {
  std::string out = "[";
  for (const double value : numbers) {
    if (out.size() > 1) out += ",";
    out += exact_number(value);
  }
  return out + "]";
}

// Joins the non-empty parts with single spaces.
void append_word(std::string& text, const char* label, const std::string& value) {
  if (value.empty()) return;
  if (!text.empty()) text += ' ';
  text += label;
  text += value;
}

std::string identity_text(const SensorIdentity& id) {
  std::string text;
  append_word(text, "", id.vendor);
  append_word(text, "", id.model);
  append_word(text, "serial ", id.serial);
  append_word(text, "firmware ", id.firmware);
  return text;
}

// `,"name":value` (or without the comma first), appended piece by piece: GCC 12 warns
// (-Wrestrict, wrongly) about chains of "literal" + std::string temporaries.

std::string calibration_json(const CameraCalibration& c) {
  std::string out = "{";
  json_field(out, "summary", json_string(summary(c)));
  json_field(out, "width", std::to_string(c.width));
  json_field(out, "height", std::to_string(c.height));
  json_field(out, "camera_name", json_string(c.camera_name));
  json_field(out, "distortion_model", json_string(c.distortion_model));
  json_field(out, "d", json_array(c.d));
  json_field(out, "k", json_array(c.k));
  json_field(out, "r", json_array(c.r));
  json_field(out, "p", json_array(c.p));
  json_field(out, "binning_x", std::to_string(c.binning_x));
  json_field(out, "binning_y", std::to_string(c.binning_y));
  std::string roi = "{";
  json_field(roi, "x_offset", std::to_string(c.roi.x_offset));
  json_field(roi, "y_offset", std::to_string(c.roi.y_offset));
  json_field(roi, "height", std::to_string(c.roi.height));
  json_field(roi, "width", std::to_string(c.roi.width));
  json_field(roi, "do_rectify", c.roi.do_rectify ? "true" : "false");
  json_field(out, "roi", roi + "}");
  return out + "}";
}

}  // namespace

std::array<double, 3> roll_pitch_yaw(const Mounting& m) noexcept {
  const double x = m.rotation[0], y = m.rotation[1], z = m.rotation[2], w = m.rotation[3];
  const double roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
  const double pitch = std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0));
  const double yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
  return {roll, pitch, yaw};
}

std::string describe_sensor(const SensorInfo& info) {
  std::string text = "frame ";
  text += info.frame_id;
  text += " in ";
  text += info.parent_frame;
  if (info.mounting) {
    const auto& t = info.mounting->translation;
    const auto rpy = roll_pitch_yaw(*info.mounting);
    for (const auto& [label, value] : {std::pair{" at x ", t[0]}, {" y ", t[1]}, {" z ", t[2]},
                                       {" m, rpy ", rpy[0]}, {" ", rpy[1]}, {" ", rpy[2]}}) {
      text += label;
      text += short_number(value);
    }
    text += " rad";
  } else {
    text += " (mounting unknown)";
  }
  if (info.calibration) {
    text += "; calibration ";
    text += summary(*info.calibration);
  }
  if (!info.calibration_source.empty()) {
    text += info.calibration ? " from " : "; calibration from ";
    text += info.calibration_source;
  }
  if (const std::string id = identity_text(info.identity); !id.empty()) {
    text += "; ";
    text += id;
  }
  text += "; time ";
  text += to_string(info.time_base);
  if (!info.time_sync.empty()) {
    text += " (";
    text += info.time_sync;
    text += ")";
  }
  return text;
}

std::string sensor_json(const SensorInfo& info) {
  std::string out = "{";
  json_field(out, "frame_id", json_string(info.frame_id));
  json_field(out, "parent_frame", json_string(info.parent_frame));
  if (info.mounting) {
    std::string mounting = "{";
    json_field(mounting, "translation", json_array(info.mounting->translation));
    json_field(mounting, "rotation", json_array(info.mounting->rotation));
    json_field(mounting, "rpy", json_array(roll_pitch_yaw(*info.mounting)));
    json_field(out, "mounting", mounting + "}");
  } else {
    json_field(out, "mounting", "null");
  }
  json_field(out, "calibration", info.calibration ? calibration_json(*info.calibration) : "null");
  std::string identity = "{";
  json_field(identity, "vendor", json_string(info.identity.vendor));
  json_field(identity, "model", json_string(info.identity.model));
  json_field(identity, "serial", json_string(info.identity.serial));
  json_field(identity, "firmware", json_string(info.identity.firmware));
  json_field(out, "identity", identity + "}");
  json_field(out, "calibration_source", json_string(info.calibration_source));
  json_field(out, "time_base", json_string(to_string(info.time_base)));
  json_field(out, "time_sync", json_string(info.time_sync));
  json_field(out, "point_time", json_string(to_string(info.point_time)));
  return out + "}";
}

std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", c);
      out += code;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

void json_field(std::string& out, const char* name, const std::string& value) {
  if (out.size() > 1) out += ',';
  out += '"';
  out += name;
  out += "\":";
  out += value;
}

}  // namespace sim::apps
