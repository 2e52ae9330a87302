// SPDX-License-Identifier: Apache-2.0
// The built-in page's pictures: the newest frame of a stream as JPEG, a camera image as it is or
// a LiDAR frame from above. A stream gets a reader only once the page asks for it, each picture
// is made at most once per frame however many browsers ask, and a frame is copied out of shared
// memory (Reader::read), so the writer is never held up by a slow encode.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "jpeg.hpp"
#include "projection.hpp"
#include "sim/reader.hpp"
#include "top_down.hpp"

namespace sim::foxglove {

using Jpeg = std::shared_ptr<const std::vector<std::byte>>;

// A picture for the page and one line that says what it shows (size, scale, frame).
struct Picture {
  Jpeg jpeg;
  std::string caption;
};

namespace testing {
// Defined only by tests (a weak symbol: sim_foxglove itself has none, and nothing is called).
// Called on the thread that makes a picture, before it makes it, so a test can hold the
// renderer and show that nothing but the pictures waits for it.
void before_picture() __attribute__((weak));
}  // namespace testing

class PageFrames {
 public:
  PageFrames(int jpeg_quality, Trust trust) : quality_(jpeg_quality), trust_(std::move(trust)) {}

  // The error is one sentence (no frame yet, not an image stream, …).
  Expected<Picture> image(const std::string& stream);
  Expected<Picture> top_down(const std::string& stream, const TopDownOptions& options);
  // The newest frame of `lidar` drawn into the newest image of `camera`: `lidar_to_camera` and
  // `calibration` come from the streams' descriptions.
  Expected<Picture> projection(const std::string& camera, const std::string& lidar,
                               const Pose& lidar_to_camera, const CameraCalibration& calibration);
  // Closes the readers of streams that are not in `names` any more.
  void keep_only(const std::set<std::string>& names);

 private:
  struct Entry {
    std::mutex mutex;
    std::optional<Reader> reader;
    std::vector<std::byte> frame;
    FrameInfo info{};
    bool have_frame = false;
    std::optional<ImageToJpeg> jpeg;
    std::string picture_key;  // what `picture` shows: seq and options
    // What a projection `picture` was drawn with: the whole calibration and pose, not a few
    // numbers of it, so a recalibration of a paused stream is drawn anew (review L5).
    std::optional<CameraCalibration> picture_calibration;
    Pose picture_pose;
    Picture picture;
    std::vector<std::uint8_t> bgr;  // the image drawn on (projections)
  };
  std::shared_ptr<Entry> entry(const std::string& stream);
  // Copies the newest frame into the entry, if there is a newer one; the error is one sentence.
  std::optional<Error> refresh(Entry& e, const std::string& stream) const;
  // Refreshes the entry and checks it holds a frame of `kind`; the error is one sentence.
  std::optional<Error> newest(Entry& e, const std::string& stream, LayoutKind kind) const;

  const int quality_;
  const Trust trust_;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Entry>> entries_;
};

}  // namespace sim::foxglove
