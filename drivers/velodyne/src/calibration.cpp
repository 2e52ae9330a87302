// SPDX-License-Identifier: Apache-2.0
// Two readers of outside text (the user's files): a small reader for the subset of YAML the
// ros-drivers/velodyne calibration files use, and one for the boost-serialization XML of an
// HDL-64E's db.xml. Neither reads past the text; every problem is one sentence with the line.
#include "sim/velodyne/calibration.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numeric>
#include <optional>
#include <sstream>

namespace sim::velodyne {
namespace {

constexpr std::size_t max_lasers = 128;
constexpr double pi = 3.14159265358979323846;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::optional<double> parse_number(std::string_view s) noexcept {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc{} || end != s.data() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::string shown(std::string_view text) {
  std::string out;
  for (char c : text.substr(0, 40)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  return "'" + out + (text.size() > 40 ? "...'" : "'");
}

// The value a YAML laser key sets, or nullptr for a key the decoder does not use.
double* laser_field(LaserCorrection& l, std::string_view key) noexcept {
  if (key == "rot_correction") return &l.rot_correction;
  if (key == "vert_correction") return &l.vert_correction;
  if (key == "dist_correction") return &l.dist_correction;
  if (key == "dist_correction_x") return &l.dist_correction_x;
  if (key == "dist_correction_y") return &l.dist_correction_y;
  if (key == "vert_offset_correction") return &l.vert_offset_correction;
  if (key == "horiz_offset_correction") return &l.horiz_offset_correction;
  if (key == "focal_distance") return &l.focal_distance;
  if (key == "focal_slope") return &l.focal_slope;
  if (key == "min_intensity") return &l.min_intensity;
  if (key == "max_intensity") return &l.max_intensity;
  return nullptr;
}

struct ParsedLaser {
  LaserCorrection correction;
  std::optional<double> id;
  std::size_t line = 0;
};

// Puts the lasers in laser_id order and checks the set is 0…n-1 exactly once each.
Expected<std::vector<LaserCorrection>> order_lasers(std::vector<ParsedLaser>& parsed,
                                                    std::string_view source) {
  if (parsed.empty()) return invalid(std::string(source) + " lists no lasers; give a Velodyne calibration (ros-drivers/velodyne YAML or an HDL-64E db.xml).");
  if (parsed.size() > max_lasers) {
    return invalid(std::string(source) + " lists " + std::to_string(parsed.size()) +
                   " lasers, more than the 128 any Velodyne has.");
  }
  std::vector<LaserCorrection> lasers(parsed.size());
  std::vector<bool> seen(parsed.size(), false);
  for (const ParsedLaser& p : parsed) {
    const std::string where = std::string(source) + ":" + std::to_string(p.line);
    if (!p.id) return invalid(where + ": a laser without laser_id; give every laser its number.");
    const double id = *p.id;
    if (id < 0 || id >= static_cast<double>(parsed.size()) || id != std::floor(id) ||
        seen[static_cast<std::size_t>(id)]) {
      return invalid(where + ": laser_id " + std::to_string(static_cast<long long>(id)) +
                     " is not one of 0.." + std::to_string(parsed.size() - 1) +
                     " or appears twice; the file must number its lasers from 0 without gaps.");
    }
    const LaserCorrection& c = p.correction;
    if (std::abs(c.rot_correction) > pi || std::abs(c.vert_correction) > pi / 2 ||
        c.max_intensity < c.min_intensity) {
      return invalid(where + ": laser " + std::to_string(static_cast<int>(id)) +
                     " has an angle beyond ±π (radians expected) or min_intensity above max_intensity.");
    }
    seen[static_cast<std::size_t>(id)] = true;
    lasers[static_cast<std::size_t>(id)] = c;
  }
  return lasers;
}

}  // namespace

Calibration::Calibration(std::vector<LaserCorrection> lasers, double resolution_m)
    : lasers_(std::move(lasers)), rings_(lasers_.size()), file_resolution_m_(resolution_m) {
  std::vector<std::size_t> order(lasers_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lasers_[a].vert_correction < lasers_[b].vert_correction;
  });
  for (std::size_t ring = 0; ring < order.size(); ++ring) rings_[order[ring]] = static_cast<std::uint16_t>(ring);
}

Expected<Calibration> Calibration::from_lasers(std::vector<LaserCorrection> lasers) {
  if (lasers.empty() || lasers.size() > max_lasers) {
    return invalid("a calibration needs 1 to 128 lasers, not " + std::to_string(lasers.size()) + ".");
  }
  return Calibration(std::move(lasers), 0);
}

Expected<Calibration> Calibration::parse_yaml(std::string_view text, std::string_view source) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::vector<ParsedLaser> parsed;
  std::optional<double> num_lasers;
  double resolution = 0;
  bool in_lasers = false;
  std::size_t line_number = 0;
  while (!text.empty()) {
    ++line_number;
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    line = line.substr(0, line.find('#'));
    const bool indented = !line.empty() && (line.front() == ' ' || line.front() == '\t');
    line = trim(line);
    if (line.empty() || line == "---") continue;
    if (line.front() == '-') {  // a new item of the lasers sequence
      if (!in_lasers) return invalid(std::string(source) + ":" + std::to_string(line_number) + ": a list item outside 'lasers:'.");
      if (parsed.size() == max_lasers) return invalid(std::string(source) + " lists more than the 128 lasers any Velodyne has.");
      parsed.push_back(ParsedLaser{{}, std::nullopt, line_number});
      line.remove_prefix(1);
    }
    // The rest is "key: value" pairs separated by commas and braces.
    std::size_t start = 0;
    for (std::size_t i = 0; i <= line.size(); ++i) {
      if (i < line.size() && line[i] != ',' && line[i] != '{' && line[i] != '}') continue;
      const std::string_view pair = trim(line.substr(start, i - start));
      start = i + 1;
      if (pair.empty()) continue;
      const std::size_t colon = pair.find(':');
      const std::string where = std::string(source) + ":" + std::to_string(line_number);
      if (colon == std::string_view::npos) return invalid(where + ": " + shown(pair) + " is not 'key: value'.");
      const std::string_view key = trim(pair.substr(0, colon));
      const std::string_view value_text = trim(pair.substr(colon + 1));
      if (key == "lasers" && value_text.empty()) {
        in_lasers = true;
        continue;
      }
      if (!indented && (key == "num_lasers" || key == "distance_resolution")) {
        const auto value = parse_number(value_text);
        if (!value) return invalid(where + ": " + std::string(key) + " " + shown(value_text) + " is not a number.");
        if (key == "num_lasers") {
          num_lasers = value;
        } else {
          resolution = *value;
        }
        in_lasers = false;  // a top-level key ends the lasers sequence
        continue;
      }
      if (parsed.empty() || !in_lasers) continue;  // a key this reader does not use
      ParsedLaser& laser = parsed.back();
      if (key == "two_pt_correction_available") continue;  // derived from the X/Y values
      double* field = key == "laser_id" ? nullptr : laser_field(laser.correction, key);
      if (key != "laser_id" && field == nullptr) continue;
      const auto value = parse_number(value_text);
      if (!value) return invalid(where + ": " + std::string(key) + " " + shown(value_text) + " is not a number.");
      if (key == "laser_id") {
        laser.id = value;
      } else {
        *field = *value;
      }
    }
  }
  auto lasers = order_lasers(parsed, source);
  if (!lasers) return lasers.error();
  if (num_lasers && *num_lasers != static_cast<double>(lasers->size())) {
    return invalid(std::string(source) + " says num_lasers " + std::to_string(static_cast<long long>(*num_lasers)) +
                   " but lists " + std::to_string(lasers->size()) + " lasers; fix the file.");
  }
  return Calibration(std::move(lasers.value()), resolution);
}

namespace {

// The text between <tag …> and </tag> from `from`, and where it ends; nullopt when absent.
struct Element {
  std::string_view inner;
  std::size_t end = 0;
};

std::optional<Element> find_element(std::string_view text, std::string_view tag, std::size_t from = 0) {
  while (true) {
    const std::size_t open = text.find('<', from);
    if (open == std::string_view::npos) return std::nullopt;
    from = open + 1;
    if (text.substr(open + 1, tag.size()) != tag) continue;
    const std::size_t after = open + 1 + tag.size();
    if (after >= text.size() || (text[after] != '>' && text[after] != ' ' && text[after] != '/')) continue;
    const std::size_t gt = text.find('>', after);
    if (gt == std::string_view::npos) return std::nullopt;
    if (text[gt - 1] == '/') return Element{{}, gt + 1};  // <tag/>: empty
    const std::string close = "</" + std::string(tag) + ">";
    const std::size_t end = text.find(close, gt + 1);
    if (end == std::string_view::npos) return std::nullopt;
    return Element{text.substr(gt + 1, end - gt - 1), end + close.size()};
  }
}

// The <item> values of a list such as <minIntensity_>…<item>40</item>…</minIntensity_>.
std::vector<std::string_view> items(std::string_view list) {
  std::vector<std::string_view> out;
  std::size_t from = 0;
  while (auto item = find_element(list, "item", from)) {
    out.push_back(trim(item->inner));
    from = item->end;
    if (out.size() > max_lasers) break;
  }
  return out;
}

}  // namespace

Expected<Calibration> Calibration::parse_db_xml(std::string_view text, std::string_view source) {
  const std::string name(source);
  const auto db = find_element(text, "DB");
  if (!db) return invalid(name + " has no <DB> element; is it an HDL-64E db.xml?");
  double resolution = 0.002;
  if (auto lsb = find_element(db->inner, "distLSB_")) {
    const auto cm = parse_number(lsb->inner);
    if (!cm || *cm <= 0) return invalid(name + ": distLSB_ " + shown(lsb->inner) + " is not a positive number.");
    resolution = *cm * 0.01;
  }
  const auto points = find_element(db->inner, "points_");
  if (!points) return invalid(name + " has no <points_> list of lasers.");
  std::vector<ParsedLaser> parsed;
  std::size_t from = 0;
  while (auto px = find_element(points->inner, "px", from)) {
    from = px->end;
    if (parsed.size() == max_lasers) return invalid(name + " lists more than the 128 lasers any Velodyne has.");
    ParsedLaser laser;
    laser.line = parsed.size() + 1;
    struct Field { const char* tag; double* out; double scale; };
    LaserCorrection& c = laser.correction;
    constexpr double deg = pi / 180.0;
    constexpr double cm = 0.01;
    const Field fields[] = {{"rotCorrection_", &c.rot_correction, deg},
                            {"vertCorrection_", &c.vert_correction, deg},
                            {"distCorrection_", &c.dist_correction, cm},
                            {"distCorrectionX_", &c.dist_correction_x, cm},
                            {"distCorrectionY_", &c.dist_correction_y, cm},
                            {"vertOffsetCorrection_", &c.vert_offset_correction, cm},
                            {"horizOffsetCorrection_", &c.horiz_offset_correction, cm},
                            {"focalDistance_", &c.focal_distance, cm},
                            {"focalSlope_", &c.focal_slope, 1.0}};
    if (auto id = find_element(px->inner, "id_")) laser.id = parse_number(id->inner);
    for (const Field& f : fields) {
      const auto element = find_element(px->inner, f.tag);
      if (!element) continue;
      const auto value = parse_number(element->inner);
      if (!value) {
        return invalid(name + ": laser " + std::to_string(parsed.size()) + " has " + f.tag + " " +
                       shown(element->inner) + ", not a number.");
      }
      *f.out = *value * f.scale;
    }
    parsed.push_back(laser);
  }
  for (const char* tag : {"minIntensity_", "maxIntensity_"}) {
    const auto list = find_element(db->inner, tag);
    if (!list) continue;
    const auto values = items(list->inner);
    for (std::size_t i = 0; i < values.size() && i < parsed.size(); ++i) {
      const auto value = parse_number(values[i]);
      if (!value) return invalid(name + ": " + tag + " item " + std::to_string(i) + " is not a number.");
      (tag[1] == 'i' ? parsed[i].correction.min_intensity : parsed[i].correction.max_intensity) = *value;
    }
  }
  auto lasers = order_lasers(parsed, source);
  if (!lasers) return lasers.error();
  return Calibration(std::move(lasers.value()), resolution);
}

Expected<Calibration> Calibration::load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return Error{ErrorCode::not_found, "cannot read the calibration file " + path.string() +
                                           "; check the path (--calibration)."};
  }
  std::ostringstream text;
  text << in.rdbuf();
  const std::string content = text.str();
  const std::string source = path.filename().string();
  const std::string_view start = trim(content);
  if (!start.empty() && start.front() == '<') return parse_db_xml(content, source);
  return parse_yaml(content, source);
}

}  // namespace sim::velodyne
