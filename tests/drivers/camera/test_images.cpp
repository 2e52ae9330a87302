// SPDX-License-Identifier: Apache-2.0
#include "test_images.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include <turbojpeg.h>

namespace sim::camera::testing {

Bytes scene_bgr(std::uint32_t width, std::uint32_t height, std::uint32_t seed) {
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_8UC3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<cv::Vec3b>(y, x) = {static_cast<uchar>(x * 255 / std::max(1, image.cols - 1)),
                                   static_cast<uchar>(y * 255 / std::max(1, image.rows - 1)),
                                   static_cast<uchar>((x + y + static_cast<int>(seed) * 37) % 256)};
    }
  }
  const int radius = std::max(2, image.rows / 5);
  cv::circle(image, {static_cast<int>((seed * 53) % width), image.rows / 2}, radius,
             cv::Scalar(20, 200, 240), cv::FILLED);
  cv::rectangle(image, {image.cols / 8, image.rows / 8}, {image.cols / 4, image.rows / 3},
                cv::Scalar(250, 30, 60), cv::FILLED);
  Bytes bytes(image.total() * image.elemSize());
  std::memcpy(bytes.data(), image.data, bytes.size());
  return bytes;
}

Bytes noise(std::size_t size, std::uint32_t seed) {
  std::mt19937 random(seed);
  Bytes bytes(size);
  for (auto& b : bytes) b = static_cast<std::byte>(random() & 0xff);
  return bytes;
}

Bytes encode_jpeg(std::span<const std::byte> bgr, std::uint32_t width, std::uint32_t height,
                  int quality, bool subsample_422) {
  // turbojpeg rather than cv::imencode: OpenCV 4.6 cannot choose 4:2:2, which UVC cameras send.
  tjhandle encoder = tjInitCompress();
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int rc = tjCompress2(encoder, reinterpret_cast<const unsigned char*>(bgr.data()),
                             static_cast<int>(width), 0, static_cast<int>(height), TJPF_BGR, &out,
                             &size, subsample_422 ? TJSAMP_422 : TJSAMP_420, quality, 0);
  Bytes bytes;
  if (rc == 0) bytes.assign(reinterpret_cast<std::byte*>(out), reinterpret_cast<std::byte*>(out) + size);
  tjFree(out);
  tjDestroy(encoder);
  return bytes;
}

Bytes reference(const ImageLayout& layout, std::span<const std::byte> input, imaging::OutputFormat output) {
  cv::Mat result;
  const int rows = static_cast<int>(layout.height);
  const int cols = static_cast<int>(layout.width);
  auto* data = const_cast<std::byte*>(input.data());
  const bool bgr = output == imaging::OutputFormat::bgr8;
  const bool rgb = output == imaging::OutputFormat::rgb8;
  switch (layout.format) {
    case PixelFormat::mjpeg: {
      const cv::Mat encoded(1, static_cast<int>(input.size()), CV_8UC1, data);
      result = cv::imdecode(encoded, output == imaging::OutputFormat::mono8 ? cv::IMREAD_GRAYSCALE
                                                                   : cv::IMREAD_COLOR);
      if (rgb) cv::cvtColor(result, result, cv::COLOR_BGR2RGB);
      break;
    }
    case PixelFormat::yuyv:
      cv::cvtColor(cv::Mat(rows, cols, CV_8UC2, data, layout.stride), result,
                   bgr ? cv::COLOR_YUV2BGR_YUYV : rgb ? cv::COLOR_YUV2RGB_YUYV
                                                      : cv::COLOR_YUV2GRAY_YUYV);
      break;
    case PixelFormat::uyvy:
      cv::cvtColor(cv::Mat(rows, cols, CV_8UC2, data, layout.stride), result,
                   bgr ? cv::COLOR_YUV2BGR_UYVY : rgb ? cv::COLOR_YUV2RGB_UYVY
                                                      : cv::COLOR_YUV2GRAY_UYVY);
      break;
    case PixelFormat::mono8: {
      const cv::Mat grey(rows, cols, CV_8UC1, data, layout.stride);
      if (bgr || rgb) {
        cv::cvtColor(grey, result, cv::COLOR_GRAY2BGR);
      } else {
        result = grey.clone();
      }
      break;
    }
    case PixelFormat::mono16: {
      cv::Mat grey;
      cv::Mat(rows, cols, CV_16UC1, data, layout.stride).convertTo(grey, CV_8U, 1.0 / 256.0);
      if (bgr || rgb) {
        cv::cvtColor(grey, result, cv::COLOR_GRAY2BGR);
      } else {
        result = grey;
      }
      break;
    }
    case PixelFormat::bgr8: {
      const cv::Mat image(rows, cols, CV_8UC3, data, layout.stride);
      if (bgr) result = image.clone();
      if (rgb) cv::cvtColor(image, result, cv::COLOR_BGR2RGB);
      if (output == imaging::OutputFormat::mono8) cv::cvtColor(image, result, cv::COLOR_BGR2GRAY);
      break;
    }
    case PixelFormat::rgb8: {
      const cv::Mat image(rows, cols, CV_8UC3, data, layout.stride);
      if (bgr) cv::cvtColor(image, result, cv::COLOR_RGB2BGR);
      if (rgb) result = image.clone();
      if (output == imaging::OutputFormat::mono8) cv::cvtColor(image, result, cv::COLOR_RGB2GRAY);
      break;
    }
    case PixelFormat::bayer_rggb8: {
      // OpenCV names Bayer patterns after the second row's first two pixels: RGGB is "BG".
      const cv::Mat mosaic(rows, cols, CV_8UC1, data, layout.stride);
      if (bgr) cv::cvtColor(mosaic, result, cv::COLOR_BayerBG2BGR);
      if (rgb) cv::cvtColor(mosaic, result, cv::COLOR_BayerBG2RGB);
      if (output == imaging::OutputFormat::mono8) cv::cvtColor(mosaic, result, cv::COLOR_BayerBG2GRAY);
      break;
    }
    default:
      return {};
  }
  if (result.empty()) return {};
  if (!result.isContinuous()) result = result.clone();
  Bytes bytes(result.total() * result.elemSize());
  std::memcpy(bytes.data(), result.data, bytes.size());
  return bytes;
}

int max_difference(std::span<const std::byte> a, std::span<const std::byte> b) {
  if (a.size() != b.size()) return 255;
  int worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i])));
  }
  return worst;
}

}  // namespace sim::camera::testing
