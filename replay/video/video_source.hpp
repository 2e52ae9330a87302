// SPDX-License-Identifier: Apache-2.0
// Frames of a video file (OpenCV's FFmpeg backend) or of a folder of images, in file order,
// as BGR matrices; rewinds for --loop.
#pragma once

#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

#include "sim/result.hpp"

namespace sim::replay {

class VideoSource {
 public:
  virtual ~VideoSource() = default;
  // The next frame into `frame` (reusing its memory); false at the end.
  virtual bool next(cv::Mat& frame) = 0;
  virtual bool rewind() = 0;
  virtual double fps() const = 0;               // 0 when the source does not say
  virtual long long frame_count() const = 0;    // 0 when unknown
  virtual std::string describe() const = 0;
  // True when next() returns each frame's JPEG bytes (a 1×N CV_8UC1 matrix) instead of pixels:
  // MJPEG files then take the same libjpeg-turbo path into the slot as a UVC camera's frames.
  virtual bool jpeg_frames() const { return false; }
  virtual int width() const { return 0; }   // of jpeg_frames() sources
  virtual int height() const { return 0; }

  // A file through cv::CAP_FFMPEG (Debian's GStreamer backend lacks the decoders), or a folder
  // of .png/.jpg/.bmp/.tif/.ppm/.pgm/.webp images sorted by name.
  static Expected<std::unique_ptr<VideoSource>> open(const std::string& path);
};

}  // namespace sim::replay
