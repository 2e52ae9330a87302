// SPDX-License-Identifier: Apache-2.0
#include "video_source.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <system_error>
#include <vector>

namespace sim::replay {

namespace {

namespace fs = std::filesystem;

class FileSource final : public VideoSource {
 public:
  explicit FileSource(std::string path) : path_(std::move(path)) {}
  bool open() {
    capture_.open(path_, cv::CAP_FFMPEG);
    if (!capture_.isOpened()) return false;
    // Motion-JPEG: ask FFmpeg for the undecoded packets and decode them ourselves.
    const auto fourcc = static_cast<int>(capture_.get(cv::CAP_PROP_FOURCC));
    jpeg_ = fourcc == cv::VideoWriter::fourcc('M', 'J', 'P', 'G') &&
            capture_.set(cv::CAP_PROP_FORMAT, -1);
    return true;
  }
  bool jpeg_frames() const override { return jpeg_; }
  int width() const override { return static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH)); }
  int height() const override { return static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT)); }
  bool next(cv::Mat& frame) override { return capture_.read(frame) && !frame.empty(); }
  // Reopening is more reliable than seeking to frame 0 in every container and codec.
  bool rewind() override {
    capture_.release();
    return open();
  }
  double fps() const override { return capture_.get(cv::CAP_PROP_FPS); }
  long long frame_count() const override {
    const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
    return count > 0 ? static_cast<long long>(count) : 0;
  }
  std::string describe() const override { return path_; }

 private:
  std::string path_;
  mutable cv::VideoCapture capture_;
  bool jpeg_ = false;
};

class FolderSource final : public VideoSource {
 public:
  FolderSource(std::string path, std::vector<fs::path> files)
      : path_(std::move(path)), files_(std::move(files)) {}
  bool next(cv::Mat& frame) override {
    while (index_ < files_.size()) {
      frame = cv::imread(files_[index_++].string(), cv::IMREAD_COLOR);
      if (!frame.empty()) return true;
      ++unreadable_;  // skipped: a broken image must not end or crash the replay
    }
    return false;
  }
  bool rewind() override {
    index_ = 0;
    return true;
  }
  double fps() const override { return 0; }
  long long frame_count() const override { return static_cast<long long>(files_.size()); }
  std::string describe() const override {
    return path_ + " (" + std::to_string(files_.size()) + " images)";
  }

 private:
  std::string path_;
  std::vector<fs::path> files_;
  std::size_t index_ = 0;
  std::size_t unreadable_ = 0;
};

bool is_image(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* known : {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm",
                            ".webp"}) {
    if (ext == known) return true;
  }
  return false;
}

}  // namespace

Expected<std::unique_ptr<VideoSource>> VideoSource::open(const std::string& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) {
    return Error{ErrorCode::not_found, "no file or folder at " + path + ": check the path"};
  }
  if (fs::is_directory(status)) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      if (entry.is_regular_file() && is_image(entry.path())) files.push_back(entry.path());
    }
    if (ec) return Error{ErrorCode::system_error, "cannot list " + path + ": " + ec.message()};
    if (files.empty()) {
      return Error{ErrorCode::invalid_argument,
                   path + " holds no images (.png, .jpg, .bmp, .tif, .ppm, .pgm, .webp)"};
    }
    std::sort(files.begin(), files.end());
    return std::unique_ptr<VideoSource>(new FolderSource(path, std::move(files)));
  }
  auto source = std::make_unique<FileSource>(path);
  if (!source->open()) {
    return Error{ErrorCode::invalid_argument,
                 "cannot read " + path +
                     " as a video: it is not a format FFmpeg decodes (try ffprobe on it)"};
  }
  return std::unique_ptr<VideoSource>(std::move(source));
}

}  // namespace sim::replay
