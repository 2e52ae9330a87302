// SPDX-License-Identifier: Apache-2.0
// Image streams to PNG. Formats PNG holds as they are (mono8, mono16, bgr8, bgra8) are written
// straight from the frame; every other one (RGB order, Bayer, packed YUV, MJPEG) goes through
// the camera drivers' own FrameDecoder to BGR first, so a dumped frame shows exactly what the
// drivers' conversions make of it.
#include <opencv2/imgcodecs.hpp>

#include "frame_sink.hpp"
#include "sim/imaging/decoder.hpp"
#include "sim/opencv.hpp"

namespace sim::dump {
namespace {

bool png_holds_as_is(PixelFormat format) {
  return format == PixelFormat::mono8 || format == PixelFormat::mono16 ||
         format == PixelFormat::bgr8 || format == PixelFormat::bgra8;
}

class PngSink final : public FrameSink {
 public:
  PngSink(const ImageLayout& layout, std::optional<imaging::FrameDecoder> decoder)
      : layout_(layout), decoder_(std::move(decoder)) {
    if (decoder_) {
      const ImageLayout& out = decoder_->output_layout();
      converted_.create(static_cast<int>(out.height), static_cast<int>(out.width), CV_8UC3);
    }
  }
  std::string extension() const override { return ".png"; }

  std::optional<Error> write(const std::filesystem::path& path, std::span<const std::byte> frame,
                             const FrameInfo& info) override {
    cv::Mat image;
    if (decoder_) {
      const auto out = std::span<std::byte>(reinterpret_cast<std::byte*>(converted_.data),
                                            converted_.total() * converted_.elemSize());
      const imaging::DecodeResult decoded = decoder_->decode(frame, out);
      if (decoded.status != imaging::DecodeStatus::ok) {
        return Error{ErrorCode::invalid_argument,
                     "frame " + std::to_string(info.seq) + " (" + sim::to_string(layout_.format) +
                         ") does not decode: " + imaging::to_string(decoded.status) +
                         "; nothing was written."};
      }
      image = converted_;
    } else {
      image = as_mat(layout_, frame);
      if (image.empty()) {
        return Error{ErrorCode::invalid_argument,
                     "frame " + std::to_string(info.seq) + " holds " + std::to_string(frame.size()) +
                         " bytes, too few for its " + info.layout.describe() +
                         " layout; nothing was written."};
      }
    }
    bool written = false;
    try {
      written = cv::imwrite(path.string(), image);
    } catch (const cv::Exception&) {
      written = false;
    }
    if (!written) {
      return Error{ErrorCode::system_error, "cannot write " + path.string() +
                                                "; check that the folder is writable and has space."};
    }
    return std::nullopt;
  }

 private:
  ImageLayout layout_;
  std::optional<imaging::FrameDecoder> decoder_;
  cv::Mat converted_;  // kept between frames: BGR pixels of a converted frame
};

}  // namespace

Expected<std::unique_ptr<FrameSink>> make_image_sink(const ImageLayout& layout,
                                                     const SinkOptions& /*options*/) {
  if (png_holds_as_is(layout.format)) {
    if (cv_type(layout) < 0 || layout.width == 0 || layout.height == 0) {
      return Error{ErrorCode::invalid_argument,
                   "the stream's image layout (" + std::to_string(layout.width) + "x" +
                       std::to_string(layout.height) + ") is empty; restart its writer."};
    }
    return std::unique_ptr<FrameSink>(new PngSink(layout, std::nullopt));
  }
  auto decoder = imaging::FrameDecoder::create(layout, imaging::OutputFormat::bgr8);
  if (!decoder) {
    return Error{ErrorCode::invalid_argument,
                 "cannot write this stream's images as PNG: " + decoder.error().message + "."};
  }
  return std::unique_ptr<FrameSink>(new PngSink(layout, std::move(decoder.value())));
}

}  // namespace sim::dump
