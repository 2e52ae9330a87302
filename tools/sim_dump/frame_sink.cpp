// SPDX-License-Identifier: Apache-2.0
#include <cstdio>
#include <string>

#include "frame_sink.hpp"
#include "sim/apps/sensor_text.hpp"

namespace sim::dump {
namespace {

class RawSink final : public FrameSink {
 public:
  std::string extension() const override { return ".bin"; }
  std::optional<Error> write(const std::filesystem::path& path, std::span<const std::byte> frame,
                             const FrameInfo& /*info*/) override {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    bool ok = file != nullptr;
    if (ok && !frame.empty()) ok = std::fwrite(frame.data(), frame.size(), 1, file) == 1;
    if (file != nullptr) ok = std::fclose(file) == 0 && ok;
    if (!ok) {
      return Error{ErrorCode::system_error, "cannot write " + path.string() +
                                                "; check that the folder is writable and has space."};
    }
    return std::nullopt;
  }
};

std::string escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(c));
      out += code;
    } else {
      out += c;
    }
  }
  return out;
}

std::string layout_json(const Layout& layout, std::uint64_t size) {
  std::string json = "{\"kind\": ";
  switch (layout.kind) {
    case LayoutKind::points: {
      const PointLayout& p = layout.points;
      json += "\"points\", \"point_type\": \"" + std::string(to_string(p.type)) +
              "\", \"point_size\": " + std::to_string(p.point_size) +
              ", \"max_points\": " + std::to_string(p.max_points) + ", \"points\": " +
              std::to_string(p.point_size != 0 ? size / p.point_size : 0);
      break;
    }
    case LayoutKind::image: {
      const ImageLayout& i = layout.image;
      json += "\"image\", \"width\": " + std::to_string(i.width) +
              ", \"height\": " + std::to_string(i.height) +
              ", \"channels\": " + std::to_string(i.channels) +
              ", \"stride\": " + std::to_string(i.stride) + ", \"format\": \"" +
              to_string(i.format) + "\", \"bit_depth\": " + std::to_string(i.bit_depth);
      break;
    }
    case LayoutKind::bytes: json += "\"bytes\""; break;
  }
  return json + ", \"description\": \"" + escaped(layout.describe()) + "\"}";
}

}  // namespace

std::unique_ptr<FrameSink> make_raw_sink() { return std::make_unique<RawSink>(); }

Expected<std::unique_ptr<FrameSink>> make_sink(const Layout& layout, const SinkOptions& options) {
  switch (layout.kind) {
    case LayoutKind::points:
      if (point_size(layout.points.type) == 0) {
        return Error{ErrorCode::invalid_argument,
                     "the stream's point type (" + std::string(to_string(layout.points.type)) +
                         ") is unknown to this sim_dump; update it."};
      }
      return make_pcd_sink(options);
    case LayoutKind::image: return make_image_sink(layout.image, options);
    case LayoutKind::bytes: return make_raw_sink();
  }
  return Error{ErrorCode::invalid_argument, "the stream's layout is unknown to this sim_dump."};
}

// The sensor's part of the sidecar: frame, transform, description, calibration file.
std::string sensor_fields(const std::optional<SensorInfo>& sensor,
                          const std::string& calibration_file) {
  using apps::json_string;
  if (!sensor) return ",\n  \"frame_id\": null,\n  \"transform\": null,\n  \"sensor\": null";
  std::string out = ",\n  \"frame_id\": ";
  out += json_string(sensor->frame_id);
  out += ",\n  \"transform\": ";
  if (sensor->mounting) {
    const auto& t = sensor->mounting->translation;
    const auto& r = sensor->mounting->rotation;
    char numbers[256];
    std::snprintf(numbers, sizeof numbers,
                  "\"translation\": [%.17g, %.17g, %.17g], \"rotation\": [%.17g, %.17g, %.17g, %.17g]",
                  t[0], t[1], t[2], r[0], r[1], r[2], r[3]);
    out += "{\"parent_frame\": ";
    out += json_string(sensor->parent_frame);
    out += ", \"child_frame\": ";
    out += json_string(sensor->frame_id);
    out += ", ";
    out += numbers;
    out += "}";
  } else {
    out += "null";
  }
  out += ",\n  \"calibration_file\": ";
  out += json_string(calibration_file);
  out += ",\n  \"sensor\": ";
  out += apps::sensor_json(*sensor);
  return out;
}

std::string sidecar_json(const std::string& stream, const FrameInfo& info,
                         const std::string& file_name, const std::optional<SensorInfo>& sensor,
                         const std::string& calibration_file) {
  return "{\n  \"stream\": \"" + escaped(stream) + "\",\n  \"file\": \"" + escaped(file_name) +
         "\",\n  \"seq\": " + std::to_string(info.seq) +
         ",\n  \"stamp_ns\": " + std::to_string(info.stamp_ns) +
         ",\n  \"receive_ns\": " + std::to_string(info.receive_ns) +
         ",\n  \"publish_ns\": " + std::to_string(info.publish_ns) +
         ",\n  \"size\": " + std::to_string(info.size) +
         ",\n  \"layout\": " + layout_json(info.layout, info.size) +
         sensor_fields(sensor, calibration_file) + "\n}\n";
}

}  // namespace sim::dump
