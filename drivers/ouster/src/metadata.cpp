// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/metadata.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace sim::ouster {
namespace {

using Json = nlohmann::json;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// The key at the top level (FW 2.x) or in the section FW 3.x moved it to. Null when absent.
const Json* find(const Json& root, std::string_view section, std::string_view key) {
  if (!section.empty()) {
    auto s = root.find(section);
    if (s != root.end() && s->is_object()) {
      auto v = s->find(key);
      if (v != s->end()) return &*v;
    }
  }
  auto v = root.find(key);
  return v != root.end() ? &*v : nullptr;
}

std::string where(std::string_view section, std::string_view key) {
  return section.empty() ? std::string(key) : std::string(section) + "." + std::string(key);
}

std::string text_of(const Json& root, std::string_view section, std::string_view key) {
  const Json* v = find(root, section, key);
  if (v == nullptr) return {};
  if (v->is_string()) return v->get<std::string>();
  if (v->is_number_unsigned()) return std::to_string(v->get<std::uint64_t>());
  return {};
}

Expected<double> number(const Json& v, const std::string& name) {
  if (!v.is_number()) return invalid("metadata key " + name + " is not a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) return invalid("metadata key " + name + " is not a finite number");
  return d;
}

Expected<unsigned> count(const Json& root, std::string_view section, std::string_view key) {
  const Json* v = find(root, section, key);
  const std::string name = where(section, key);
  if (v == nullptr) return invalid("the metadata has no " + name + "; it is not an Ouster sensor's metadata JSON");
  if (!v->is_number_integer() || v->get<std::int64_t>() < 0 || v->get<std::int64_t>() > 65535) {
    return invalid("metadata key " + name + " is not a count from 0 to 65535");
  }
  return static_cast<unsigned>(v->get<std::int64_t>());
}

Expected<std::vector<double>> numbers(const Json& root, std::string_view section,
                                      std::string_view key, std::size_t size) {
  const Json* v = find(root, section, key);
  const std::string name = where(section, key);
  if (v == nullptr) return invalid("the metadata has no " + name + "; it is not an Ouster sensor's metadata JSON");
  if (!v->is_array() || v->size() != size) {
    return invalid("metadata key " + name + " must be a list of " + std::to_string(size) + " numbers");
  }
  std::vector<double> out;
  out.reserve(size);
  for (const Json& item : *v) {
    auto d = number(item, name);
    if (!d) return d.error();
    out.push_back(*d);
  }
  return out;
}

Expected<std::array<double, 16>> matrix(const Json& root, std::string_view section,
                                        std::string_view key) {
  auto values = numbers(root, section, key, 16);
  if (!values) return values.error();
  std::array<double, 16> m{};
  for (std::size_t i = 0; i < 16; ++i) m[i] = (*values)[i];
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) {
    return invalid("metadata key " + where(section, key) +
                   " is not a homogeneous transform (its last row must be 0 0 0 1)");
  }
  return m;
}

std::array<double, 16> identity() {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

// The sections' names in firmware 3.x metadata.
constexpr std::string_view beams_section = "beam_intrinsics";
constexpr std::string_view lidar_section = "lidar_intrinsics";
constexpr std::string_view imu_section = "imu_intrinsics";
constexpr std::string_view config_section = "config_params";
constexpr std::string_view info_section = "sensor_info";

// FW 2.x keeps the format in "data_format", FW 3.x in "lidar_data_format".
std::string_view format_section(const Json& root) {
  if (root.contains("lidar_data_format")) return "lidar_data_format";
  return "data_format";
}

Expected<void> read_format(const Json& root, Metadata& m) {
  const std::string_view fs = format_section(root);
  if (!root.contains(fs) || !root[std::string(fs)].is_object()) {
    return invalid("the metadata has no data_format (FW 2.x) or lidar_data_format (FW 3.x) "
                   "section; it is not an Ouster sensor's metadata JSON");
  }
  auto h = count(root, fs, "pixels_per_column");
  if (!h) return h.error();
  auto w = count(root, fs, "columns_per_frame");
  if (!w) return w.error();
  auto cpp = count(root, fs, "columns_per_packet");
  if (!cpp) return cpp.error();
  // FW 2.0 sensors without the key send LEGACY packets.
  std::string profile_name = text_of(root, fs, "udp_profile_lidar");
  if (profile_name.empty()) profile_name = text_of(root, config_section, "udp_profile_lidar");
  if (profile_name.empty()) profile_name = "LEGACY";
  const auto profile = parse_profile(profile_name);
  if (!profile) {
    return invalid("the metadata's lidar profile " + profile_name + " is not supported (" +
                   std::string(profile_names()) + ")");
  }
  const bool fusa = text_of(root, fs, "header_type") == "FUSA";
  auto format = PacketFormat::create(*profile, *h, *cpp, *w, fusa);
  if (!format) return invalid("the metadata's " + format.error().message);
  m.format = *format;
  auto shifts = numbers(root, fs, "pixel_shift_by_row", *h);
  if (!shifts) return shifts.error();
  for (double s : *shifts) {
    if (s != std::floor(s) || std::fabs(s) > *w) {
      return invalid("metadata key pixel_shift_by_row holds " + std::to_string(s) +
                     ", not a whole column shift");
    }
    m.pixel_shift_by_row.push_back(static_cast<int>(s));
  }
  m.column_window = {0, *w - 1};
  if (const Json* window = find(root, fs, "column_window"); window != nullptr) {
    if (!window->is_array() || window->size() != 2 || !(*window)[0].is_number_integer() ||
        !(*window)[1].is_number_integer() || (*window)[0].get<std::int64_t>() < 0 ||
        (*window)[1].get<std::int64_t>() < 0 || (*window)[0].get<std::int64_t>() >= *w ||
        (*window)[1].get<std::int64_t>() >= *w) {
      return invalid("metadata key column_window must be two column indices below " +
                     std::to_string(*w));
    }
    m.column_window = {static_cast<unsigned>((*window)[0].get<std::int64_t>()),
                       static_cast<unsigned>((*window)[1].get<std::int64_t>())};
  }
  return {};
}

Expected<void> read_geometry(const Json& root, Metadata& m) {
  const unsigned h = m.format.pixels_per_column;
  auto altitude = numbers(root, beams_section, "beam_altitude_angles", h);
  if (!altitude) return invalid(altitude.error().message + " (one per beam: pixels_per_column)");
  auto azimuth = numbers(root, beams_section, "beam_azimuth_angles", h);
  if (!azimuth) return invalid(azimuth.error().message + " (one per beam: pixels_per_column)");
  m.beam_altitude_deg = std::move(*altitude);
  m.beam_azimuth_deg = std::move(*azimuth);
  for (std::size_t i = 0; i < h; ++i) {
    if (std::fabs(m.beam_altitude_deg[i]) > 90 || std::fabs(m.beam_azimuth_deg[i]) > 360) {
      return invalid("beam " + std::to_string(i) + "'s angles are out of range (altitude ±90°, "
                     "azimuth ±360°); check the metadata");
    }
  }
  // FW 3.x: beam_to_lidar_transform; FW 2.x: the radius alone.
  if (find(root, beams_section, "beam_to_lidar_transform") != nullptr) {
    auto t = matrix(root, beams_section, "beam_to_lidar_transform");
    if (!t) return t.error();
    m.beam_to_lidar = *t;
  } else {
    m.beam_to_lidar = identity();
  }
  if (const Json* n = find(root, beams_section, "lidar_origin_to_beam_origin_mm"); n != nullptr) {
    auto d = number(*n, "lidar_origin_to_beam_origin_mm");
    if (!d) return d.error();
    m.lidar_origin_to_beam_origin_mm = *d;
    if (find(root, beams_section, "beam_to_lidar_transform") == nullptr) m.beam_to_lidar[3] = *d;
  } else if (find(root, beams_section, "beam_to_lidar_transform") != nullptr) {
    m.lidar_origin_to_beam_origin_mm = std::hypot(m.beam_to_lidar[3], m.beam_to_lidar[11]);
  } else {
    // Neither (FW 1.14 and older): ouster-sdk's defaults by product line (sensor_info.cpp).
    const std::string line = text_of(root, info_section, "prod_line");
    const auto starts = [&line](std::string_view p) { return line.rfind(p, 0) == 0; };
    const double origin = starts("OS-0-") ? 27.67 : starts("OS-1-") ? 15.806 : starts("OS-2-") ? 13.762 : 12.163;
    m.lidar_origin_to_beam_origin_mm = origin;
    m.beam_to_lidar[3] = origin;
  }
  if (find(root, lidar_section, "lidar_to_sensor_transform") == nullptr) {
    return invalid("the metadata has no lidar_to_sensor_transform; points cannot be put in the "
                   "sensor frame");
  }
  auto l2s = matrix(root, lidar_section, "lidar_to_sensor_transform");
  if (!l2s) return l2s.error();
  m.lidar_to_sensor = *l2s;
  m.imu_to_sensor = identity();
  if (find(root, imu_section, "imu_to_sensor_transform") != nullptr) {
    auto i2s = matrix(root, imu_section, "imu_to_sensor_transform");
    if (!i2s) return i2s.error();
    m.imu_to_sensor = *i2s;
  }
  return {};
}

void read_identity(const Json& root, Metadata& m) {
  m.prod_line = text_of(root, info_section, "prod_line");
  m.serial = text_of(root, info_section, "prod_sn");
  m.firmware = text_of(root, info_section, "build_rev");
  m.lidar_mode = text_of(root, config_section, "lidar_mode");
  m.timestamp_mode = text_of(root, config_section, "timestamp_mode");
  if (const Json* id = find(root, info_section, "initialization_id");
      id != nullptr && id->is_number_unsigned() && id->get<std::uint64_t>() < (1u << 24)) {
    m.init_id = static_cast<std::uint32_t>(id->get<std::uint64_t>());
  }
  // "1024x10": the frame rate after the x.
  if (const auto x = m.lidar_mode.find('x'); x != std::string::npos) {
    const std::string hz = m.lidar_mode.substr(x + 1);
    if (hz == "5" || hz == "10" || hz == "20") m.frequency_hz = static_cast<unsigned>(std::stoi(hz));
  }
  auto port = [&](std::string_view key, std::uint16_t fallback) -> std::uint16_t {
    const Json* p = find(root, config_section, key);
    if (p == nullptr || !p->is_number_unsigned() || p->get<std::uint64_t>() == 0 ||
        p->get<std::uint64_t>() > 65535) {
      return fallback;
    }
    return static_cast<std::uint16_t>(p->get<std::uint64_t>());
  };
  m.udp_port_lidar = port("udp_port_lidar", 7502);
  m.udp_port_imu = port("udp_port_imu", 7503);
}

}  // namespace

Expected<Metadata> Metadata::parse(std::string_view json) {
  const Json root = Json::parse(json.begin(), json.end(), nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) {
    return invalid("the metadata is not valid JSON; save what the sensor's "
                   "http://SENSOR/api/v1/sensor/metadata returns");
  }
  if (!root.is_object()) return invalid("the metadata JSON is not an object; it is not an Ouster sensor's metadata");
  Metadata m;
  if (auto ok = read_format(root, m); !ok) return ok.error();
  if (auto ok = read_geometry(root, m); !ok) return ok.error();
  read_identity(root, m);
  return m;
}

Expected<Metadata> Metadata::load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return Error{ErrorCode::not_found, "cannot read the metadata file " + path.string() +
                                           "; give the sensor's metadata JSON with --calibration"};
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().size() > (16u << 20)) {
    return invalid("the metadata file " + path.string() + " is larger than 16 MB; it is not a sensor's metadata");
  }
  auto parsed = parse(text.str());
  if (!parsed) return invalid(path.string() + ": " + parsed.error().message);
  return parsed;
}

unsigned Metadata::window_columns() const noexcept {
  const unsigned w = format.columns_per_frame;
  return (column_window[1] + w - column_window[0]) % w + 1;
}

std::string Metadata::describe() const {
  std::string text = prod_line.empty() ? "Ouster sensor" : prod_line;
  if (!serial.empty() || !firmware.empty()) {
    text += " (";
    if (!serial.empty()) text += "sn " + serial;
    if (!serial.empty() && !firmware.empty()) text += ", ";
    text += firmware;
    text += ")";
  }
  return text + ", " + std::string(to_string(format.profile)) + ", " +
         std::to_string(beams()) + " beams × " + std::to_string(columns()) + " columns at " +
         std::to_string(frequency_hz) + " Hz";
}

}  // namespace sim::ouster
