// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/camera_info_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>

namespace sim::apps {
namespace {

// A calibration is a few hundred bytes; anything this large is not one.
constexpr std::uintmax_t kMaxFileBytes = 1 << 20;

// Thrown inside the parser, caught once at its edge and turned into the Error sentence.
struct Problem {
  std::string what;
};
// The same for a well-formed file whose numbers no camera has: its sentence says what to do.
struct Implausible {
  std::string what;
};

std::string line_of(const YAML::Node& node) { return std::to_string(node.Mark().line + 1); }

const YAML::Node required(const YAML::Node& root, const char* key) {
  YAML::Node node = root[key];
  if (!node.IsDefined() || node.IsNull()) throw Problem{std::string("has no '") + key + "'"};
  return node;
}

double finite_number(const YAML::Node& node, const std::string& what) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value)) {
    throw Problem{what + " (line " + line_of(node) + ") is not a number"};
  }
  if (!std::isfinite(value)) {
    throw Problem{what + " (line " + line_of(node) + ") is not a finite number"};
  }
  return value;
}

std::uint32_t whole_number(const YAML::Node& node, const std::string& what, std::uint32_t max) {
  long long value = 0;
  if (!node.IsScalar() || !YAML::convert<long long>::decode(node, value) || value < 0 ||
      static_cast<unsigned long long>(value) > max) {
    throw Problem{what + " (line " + line_of(node) + ") is not a whole number from 0 to " +
                  std::to_string(max)};
  }
  return static_cast<std::uint32_t>(value);
}

// A {rows, cols, data} matrix of exactly rows × cols finite numbers; `rows` and `cols` of 0 take
// any count (the distortion vector's length is the file's choice).
std::vector<double> matrix(const YAML::Node& root, const char* key, std::uint32_t rows,
                           std::uint32_t cols) {
  const YAML::Node node = required(root, key);
  if (!node.IsMap()) throw Problem{std::string("'") + key + "' is not a {rows, cols, data} map"};
  const std::string name = std::string("'") + key + "'";
  const std::uint32_t file_rows = whole_number(required(node, "rows"), name + " rows", 64);
  const std::uint32_t file_cols = whole_number(required(node, "cols"), name + " cols", 64);
  const YAML::Node data = required(node, "data");
  if (!data.IsSequence()) throw Problem{name + " data is not a list of numbers"};
  if ((rows != 0 && file_rows != rows) || (cols != 0 && file_cols != cols)) {
    throw Problem{name + " is " + std::to_string(file_rows) + "x" + std::to_string(file_cols) +
                  ", not " + std::to_string(rows) + "x" + (cols != 0 ? std::to_string(cols) : "N")};
  }
  if (data.size() != std::size_t{file_rows} * file_cols) {
    throw Problem{name + " has " + std::to_string(data.size()) + " numbers for " +
                  std::to_string(file_rows) + "x" + std::to_string(file_cols)};
  }
  std::vector<double> values;
  values.reserve(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    values.push_back(finite_number(data[i], name + " entry " + std::to_string(i + 1)));
  }
  return values;
}

template <std::size_t N>
std::array<double, N> fixed_matrix(const YAML::Node& root, const char* key, std::uint32_t rows,
                                   std::uint32_t cols) {
  const std::vector<double> values = matrix(root, key, rows, cols);
  std::array<double, N> result{};
  std::copy(values.begin(), values.end(), result.begin());
  return result;
}

CameraCalibration::RegionOfInterest region_of_interest(const YAML::Node& node) {
  if (!node.IsMap()) throw Problem{"'roi' is not a map of x_offset, y_offset, height, width"};
  constexpr std::uint32_t kMax = std::numeric_limits<std::uint32_t>::max();
  CameraCalibration::RegionOfInterest roi;
  roi.x_offset = whole_number(required(node, "x_offset"), "'roi' x_offset", kMax);
  roi.y_offset = whole_number(required(node, "y_offset"), "'roi' y_offset", kMax);
  roi.height = whole_number(required(node, "height"), "'roi' height", kMax);
  roi.width = whole_number(required(node, "width"), "'roi' width", kMax);
  if (const YAML::Node rectify = node["do_rectify"]; rectify.IsDefined() && !rectify.IsNull()) {
    bool value = false;
    if (!rectify.IsScalar() || !YAML::convert<bool>::decode(rectify, value)) {
      throw Problem{"'roi' do_rectify (line " + line_of(rectify) + ") is not true or false"};
    }
    roi.do_rectify = value;
  }
  return roi;
}

std::string text_of(const YAML::Node& node, const char* key) {
  if (!node.IsScalar()) throw Problem{std::string("'") + key + "' is not a string"};
  return node.Scalar();
}

// Numbers no camera has (review turn 4 L7): camera_calibration_parsers reads any, and such a
// file would be published and draw every overlay nowhere. K of zeros is an uncalibrated camera
// (ROS's convention) and R of zeros one without rectification: both are let through.
void check_plausible(const CameraCalibration& c) {
  const double fx = c.k[0], fy = c.k[4];
  const double side = std::max(c.width, c.height);
  if ((fx != 0 || fy != 0) && !(fx > 0 && fy > 0 && fx <= 1000 * side && fy <= 1000 * side)) {
    std::ostringstream what;
    what << "has focal lengths fx = " << fx << " and fy = " << fy << " in 'camera_matrix', which no "
         << c.width << "x" << c.height << " camera has (they are positive and at most 1000 times "
         << "the image's side); calibrate the camera again or fix the file";
    throw Implausible{what.str()};
  }
  if (std::all_of(c.r.begin(), c.r.end(), [](double v) { return v == 0; })) return;
  // A rotation: R times its transpose is the identity, and its determinant is +1.
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int n = 0; n < 3; ++n) dot += c.r[i * 3 + n] * c.r[j * 3 + n];
      worst = std::max(worst, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  }
  const auto& r = c.r;
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (worst > 1e-3 || det < 0) {
    throw Implausible{"has a 'rectification_matrix' that is not a rotation (R times its transpose "
                      "is not the identity, or it mirrors); calibrate the camera again or fix the file"};
  }
}

CameraCalibration calibration_from(const YAML::Node& root) {
  if (!root.IsMap()) throw Problem{"is not a map of calibration keys"};
  constexpr std::uint32_t kMaxSide = 1 << 20;
  CameraCalibration c;
  c.width = whole_number(required(root, "image_width"), "'image_width'", kMaxSide);
  c.height = whole_number(required(root, "image_height"), "'image_height'", kMaxSide);
  if (c.width == 0 || c.height == 0) throw Problem{"gives an image size of zero"};
  if (const YAML::Node name = root["camera_name"]; name.IsDefined() && !name.IsNull()) {
    // Informational, and ROS sets no limit: cut to fit the record rather than refuse the file
    // (review turn 4 L7).
    c.camera_name = sensor_text(text_of(name, "camera_name"), SensorInfo::kMaxName);
  }
  if (const YAML::Node model = root["distortion_model"]; model.IsDefined() && !model.IsNull()) {
    c.distortion_model = text_of(model, "distortion_model");
  }
  c.k = fixed_matrix<9>(root, "camera_matrix", 3, 3);
  // camera_calibration_parsers reads rows x cols values whatever the shape: 1x5 and 5x1 alike
  // (review turn 4 L7).
  c.d = matrix(root, "distortion_coefficients", 0, 0);
  if (c.d.size() > CameraCalibration::kMaxDistortion) {
    throw Problem{"has " + std::to_string(c.d.size()) + " distortion coefficients, more than " +
                  std::to_string(CameraCalibration::kMaxDistortion)};
  }
  c.r = fixed_matrix<9>(root, "rectification_matrix", 3, 3);
  c.p = fixed_matrix<12>(root, "projection_matrix", 3, 4);
  constexpr std::uint32_t kMaxBinning = 1 << 16;
  if (const YAML::Node n = root["binning_x"]; n.IsDefined() && !n.IsNull()) {
    c.binning_x = whole_number(n, "'binning_x'", kMaxBinning);
  }
  if (const YAML::Node n = root["binning_y"]; n.IsDefined() && !n.IsNull()) {
    c.binning_y = whole_number(n, "'binning_y'", kMaxBinning);
  }
  if (const YAML::Node n = root["roi"]; n.IsDefined() && !n.IsNull()) c.roi = region_of_interest(n);
  check_plausible(c);
  return c;
}

void write_number(std::ostream& out, double value) {
  char text[32];
  const auto written = std::to_chars(text, text + sizeof text, value);  // shortest exact form
  out.write(text, written.ptr - text);
}

void write_matrix(std::ostream& out, const char* key, std::size_t rows, std::size_t cols,
                  const double* data) {
  out << key << ":\n  rows: " << rows << "\n  cols: " << cols << "\n  data: [";
  for (std::size_t i = 0; i < rows * cols; ++i) {
    if (i != 0) out << ", ";
    write_number(out, data[i]);
  }
  out << "]\n";
}

// A string as a double-quoted YAML scalar, so any camera name reads back as written.
std::string yaml_quoted(std::string_view text) {
  std::string result = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') {
      result += '\\';
      result += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\x%02x", static_cast<unsigned char>(ch));
      result += escape;
    } else {
      result += ch;
    }
  }
  return result + "\"";
}

}  // namespace

Expected<CameraCalibration> parse_camera_info(std::string_view text, std::string_view source) {
  const std::string where(source);
  try {
    return calibration_from(YAML::Load(std::string(text)));
  } catch (const Problem& problem) {
    return Error{ErrorCode::invalid_argument,
                 where + " " + problem.what + "; give a camera_calibration_parsers YAML file "
                 "(as ROS's cameracalibrator writes)"};
  } catch (const Implausible& implausible) {
    return Error{ErrorCode::invalid_argument, where + " " + implausible.what};
  } catch (const YAML::Exception& e) {
    return Error{ErrorCode::invalid_argument, where + " is not valid YAML (" + e.msg +
                                                  " at line " + std::to_string(e.mark.line + 1) +
                                                  "); fix the file"};
  }
}

Expected<std::filesystem::path> camera_info_path(std::string_view location) {
  constexpr std::string_view file_scheme = "file://";
  if (location.substr(0, file_scheme.size()) == file_scheme) {
    location.remove_prefix(file_scheme.size());
    if (location.empty() || location.front() != '/') {
      return Error{ErrorCode::invalid_argument,
                   "the camera info URL must name an absolute file (file:///path/to/camera.yaml)"};
    }
  } else if (location.find("://") != std::string_view::npos) {
    return Error{ErrorCode::invalid_argument,
                 "only file:// camera info URLs are understood; give the calibration file's path"};
  }
  if (location.empty()) {
    return Error{ErrorCode::invalid_argument, "the camera info file name is empty"};
  }
  return std::filesystem::path(location);
}

Expected<CameraCalibration> load_camera_info(std::string_view location) {
  auto path = camera_info_path(location);
  if (!path) return path.error();
  const std::string name = path->string();
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(*path, error);
  if (error) {
    return Error{ErrorCode::invalid_argument, "cannot read the camera info file " + name + " (" +
                                                  error.message() + ")"};
  }
  if (size > kMaxFileBytes) {
    return Error{ErrorCode::invalid_argument,
                 "the camera info file " + name + " is " + std::to_string(size) +
                     " bytes, too large for a calibration; check the file name"};
  }
  std::ifstream in(*path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) {
    return Error{ErrorCode::invalid_argument, "cannot read the camera info file " + name};
  }
  return parse_camera_info(text.str(), "the camera info file " + name);
}

Expected<void> check_calibration_size(const CameraCalibration& c, std::uint32_t width,
                                      std::uint32_t height) {
  std::uint32_t expected_width = c.roi.width != 0 ? c.roi.width : c.width;
  std::uint32_t expected_height = c.roi.height != 0 ? c.roi.height : c.height;
  expected_width /= std::max<std::uint32_t>(c.binning_x, 1);
  expected_height /= std::max<std::uint32_t>(c.binning_y, 1);
  if (expected_width == width && expected_height == height) return {};
  return Error{ErrorCode::invalid_argument,
               "the camera calibration is for " + std::to_string(expected_width) + "x" +
                   std::to_string(expected_height) + " images but the stream's are " +
                   std::to_string(width) + "x" + std::to_string(height) +
                   "; give the calibration of this camera mode"};
}

std::string format_camera_info(const CameraCalibration& c) {
  std::ostringstream out;
  out << "image_width: " << c.width << "\nimage_height: " << c.height
      << "\ncamera_name: " << yaml_quoted(c.camera_name) << "\n";
  write_matrix(out, "camera_matrix", 3, 3, c.k.data());
  out << "distortion_model: " << yaml_quoted(c.distortion_model) << "\n";
  write_matrix(out, "distortion_coefficients", 1, c.d.size(), c.d.data());
  write_matrix(out, "rectification_matrix", 3, 3, c.r.data());
  write_matrix(out, "projection_matrix", 3, 4, c.p.data());
  if (c.binning_x != 0 || c.binning_y != 0) {
    out << "binning_x: " << c.binning_x << "\nbinning_y: " << c.binning_y << "\n";
  }
  if (c.roi != CameraCalibration::RegionOfInterest{}) {
    out << "roi:\n  x_offset: " << c.roi.x_offset << "\n  y_offset: " << c.roi.y_offset
        << "\n  height: " << c.roi.height << "\n  width: " << c.roi.width
        << "\n  do_rectify: " << (c.roi.do_rectify ? "true" : "false") << "\n";
  }
  return out.str();
}

Expected<void> save_camera_info(const std::filesystem::path& file,
                                const CameraCalibration& calibration) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << format_camera_info(calibration);
  out.close();
  if (!out) {
    return Error{ErrorCode::system_error, "cannot write the calibration file " + file.string()};
  }
  return {};
}

}  // namespace sim::apps
