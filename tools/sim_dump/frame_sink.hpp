// SPDX-License-Identifier: Apache-2.0
// Where sim_dump writes a frame: one FrameSink per stream, chosen from the stream's layout.
// Point streams go to PCD through PCL (pcd_sink.cpp, the only file that includes PCL), raw
// streams to .bin files, image streams to PNG (image_sink.cpp, through OpenCV).
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim::dump {

struct SinkOptions {
  bool ascii = false;  // PCD: ASCII instead of binary
  bool xyz_only = false;  // PCD: x y z fields (PointXYZ) instead of x y z intensity
};

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // File name extension, with its dot (".pcd").
  virtual std::string extension() const = 0;
  // Writes one frame to `path`. The error is one sentence naming the file.
  virtual std::optional<Error> write(const std::filesystem::path& path,
                                     std::span<const std::byte> frame, const FrameInfo& info) = 0;
};

// The sink for a stream's layout, or why its frames cannot be written.
Expected<std::unique_ptr<FrameSink>> make_sink(const Layout& layout, const SinkOptions& options);

// Per kind, defined in their own files.
std::unique_ptr<FrameSink> make_pcd_sink(const SinkOptions& options);
Expected<std::unique_ptr<FrameSink>> make_image_sink(const ImageLayout& layout,
                                                     const SinkOptions& options);
std::unique_ptr<FrameSink> make_raw_sink();

// The JSON sidecar written next to each frame file: the frame's metadata and layout and, when
// the stream describes its sensor, its frame, the transform from the parent frame (as
// tf2_msgs' TransformStamped: parent, child, translation m, rotation x y z w; null when the
// mounting is unknown), the whole description, and the calibration file written beside the frame
// (`calibration_file`, empty when none).
std::string sidecar_json(const std::string& stream, const FrameInfo& info,
                         const std::string& file_name, const std::optional<SensorInfo>& sensor,
                         const std::string& calibration_file);

}  // namespace sim::dump
