// SPDX-License-Identifier: Apache-2.0
// A SIM frame as the ROS 2 message Foxglove shows: images as sensor_msgs/msg/Image (or
// CompressedImage for MJPEG streams and with --compress jpeg), points as PointCloud2, in CDR
// through the project's one message layer (sim::ros2). Raw byte streams have no message.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "jpeg.hpp"
#include "sim/layout.hpp"
#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim::foxglove {

enum class ImageCompression { none, jpeg };

struct EncodeOptions {
  ImageCompression compression = ImageCompression::none;
  int jpeg_quality = 80;
  friend bool operator==(const EncodeOptions&, const EncodeOptions&) = default;
};

struct MessageSchema {
  std::string message_encoding;  // "cdr"
  std::string name;              // "sensor_msgs/msg/Image"
  std::string encoding;          // "ros2msg"
  std::string text;              // the definition with its dependencies
};

// What a stream of this layout becomes; nullopt when Foxglove has no message for it.
std::optional<MessageSchema> schema_for(const Layout& layout, const EncodeOptions& options);

// Encodes the frames of one stream; one per thread.
class FrameEncoder {
 public:
  // `frame_id` goes into every message header (the stream name without its leading slash).
  FrameEncoder(const Layout& layout, const EncodeOptions& options, std::string frame_id);

  const Layout& layout() const noexcept { return layout_; }
  void set_frame_id(std::string frame_id) { frame_id_ = std::move(frame_id); }
  // Encodes one frame into `out`, reading `frame` (which may be a borrowed slot) once.
  std::optional<Error> encode(std::span<const std::byte> frame, const FrameInfo& info,
                              std::vector<std::byte>& out);

 private:
  Layout layout_;
  EncodeOptions options_;
  std::string frame_id_;
  std::optional<ImageToJpeg> jpeg_;
  std::vector<std::byte> compressed_;
};

}  // namespace sim::foxglove
