// SPDX-License-Identifier: Apache-2.0
// The only translation unit of the driver library that includes OpenCV's imgproc and turbojpeg:
// both are heavy to compile, and every source shares this one decoder anyway.
#include "sim/imaging/decoder.hpp"

#include <turbojpeg.h>

#include <algorithm>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "sim/opencv.hpp"

namespace sim::imaging {

const char* to_string(DecodeStatus status) noexcept {
  switch (status) {
    case DecodeStatus::ok: return "ok";
    case DecodeStatus::short_input: return "short_input";
    case DecodeStatus::corrupt_input: return "corrupt_input";
    case DecodeStatus::wrong_size: return "wrong_size";
    case DecodeStatus::output_too_small: return "output_too_small";
    case DecodeStatus::failed: return "failed";
  }
  return "?";
}

namespace {

enum class Method : std::uint8_t {
  copy_rows,        // same format in and out: copy row by row, dropping the device's padding
  copy_bytes,       // raw pass-through of every input byte (keeps the padding)
  cvt_color,        // one cv::cvtColor
  mono16_to_mono8,  // keep the high byte
  mono16_to_color,  // high byte into a scratch mono image, then cvtColor
  jpeg_decode,      // tjDecompress2 straight into the destination
  jpeg_pass,        // raw MJPEG: header checked, bytes copied
};

// cv::COLOR_* code for input → output, or -1. OpenCV names Bayer patterns by the second row, so a
// sensor whose first row starts R G (RGGB) needs the BayerBG codes.
int color_code(PixelFormat in, PixelFormat out) {
  const bool bgr = out == PixelFormat::bgr8;
  const bool rgb = out == PixelFormat::rgb8;
  const bool mono = out == PixelFormat::mono8;
  switch (in) {
    case PixelFormat::yuyv:
      return bgr ? cv::COLOR_YUV2BGR_YUYV : rgb ? cv::COLOR_YUV2RGB_YUYV
                                                : mono ? cv::COLOR_YUV2GRAY_YUYV : -1;
    case PixelFormat::uyvy:
      return bgr ? cv::COLOR_YUV2BGR_UYVY : rgb ? cv::COLOR_YUV2RGB_UYVY
                                                : mono ? cv::COLOR_YUV2GRAY_UYVY : -1;
    case PixelFormat::mono8:
    case PixelFormat::mono16:
      return bgr ? cv::COLOR_GRAY2BGR : rgb ? cv::COLOR_GRAY2RGB : -1;
    case PixelFormat::bgr8:
      return rgb ? cv::COLOR_BGR2RGB : mono ? cv::COLOR_BGR2GRAY : -1;
    case PixelFormat::rgb8:
      return bgr ? cv::COLOR_RGB2BGR : mono ? cv::COLOR_RGB2GRAY : -1;
    case PixelFormat::bgra8:
      return bgr ? cv::COLOR_BGRA2BGR : rgb ? cv::COLOR_BGRA2RGB : mono ? cv::COLOR_BGRA2GRAY : -1;
    case PixelFormat::rgba8:
      return bgr ? cv::COLOR_RGBA2BGR : rgb ? cv::COLOR_RGBA2RGB : mono ? cv::COLOR_RGBA2GRAY : -1;
    case PixelFormat::bayer_rggb8:
      return bgr ? cv::COLOR_BayerBG2BGR : rgb ? cv::COLOR_BayerBG2RGB
                                               : mono ? cv::COLOR_BayerBG2GRAY : -1;
    case PixelFormat::bayer_bggr8:
      return bgr ? cv::COLOR_BayerRG2BGR : rgb ? cv::COLOR_BayerRG2RGB
                                               : mono ? cv::COLOR_BayerRG2GRAY : -1;
    case PixelFormat::bayer_gbrg8:
      return bgr ? cv::COLOR_BayerGR2BGR : rgb ? cv::COLOR_BayerGR2RGB
                                               : mono ? cv::COLOR_BayerGR2GRAY : -1;
    case PixelFormat::bayer_grbg8:
      return bgr ? cv::COLOR_BayerGB2BGR : rgb ? cv::COLOR_BayerGB2RGB
                                               : mono ? cv::COLOR_BayerGB2GRAY : -1;
    default:
      return -1;
  }
}

int tj_pixel_format(PixelFormat out) {
  switch (out) {
    case PixelFormat::bgr8: return TJPF_BGR;
    case PixelFormat::rgb8: return TJPF_RGB;
    case PixelFormat::mono8: return TJPF_GRAY;
    default: return -1;
  }
}

}  // namespace

struct FrameDecoder::Impl {
  ImageLayout in;
  ImageLayout out;
  OutputFormat output = OutputFormat::raw;
  Method method = Method::copy_rows;
  int code = -1;        // cv::COLOR_* for cvt_color / mono16_to_color
  int tj_format = -1;   // TJPF_* for jpeg_decode
  tjhandle jpeg = nullptr;
  cv::Mat scratch;      // allocated once, for the two-step mono16 → colour path

  ~Impl() {
    if (jpeg != nullptr) tjDestroy(jpeg);
  }

  // Checks a JPEG's header; the size must be what was negotiated, or the slot would overflow
  // (a camera that changes resolution mid-stream is a wrong frame, not a new layout).
  DecodeStatus check_jpeg_header(std::span<const std::byte> data) {
    if (data.size() < 4) return DecodeStatus::corrupt_input;
    int width = 0;
    int height = 0;
    int subsampling = 0;
    int colorspace = 0;
    if (tjDecompressHeader3(jpeg, reinterpret_cast<const unsigned char*>(data.data()),
                            static_cast<unsigned long>(data.size()), &width, &height,
                            &subsampling, &colorspace) != 0) {
      return DecodeStatus::corrupt_input;
    }
    if (static_cast<std::uint32_t>(width) != in.width ||
        static_cast<std::uint32_t>(height) != in.height) {
      return DecodeStatus::wrong_size;
    }
    return DecodeStatus::ok;
  }

  DecodeResult decode(std::span<const std::byte> src, std::span<std::byte> dst) {
    if (method == Method::jpeg_pass || method == Method::jpeg_decode) {
      if (const auto status = check_jpeg_header(src); status != DecodeStatus::ok) return {status, 0};
      if (method == Method::jpeg_pass) {
        if (dst.size() < src.size()) return {DecodeStatus::output_too_small, 0};
        std::memcpy(dst.data(), src.data(), src.size());
        return {DecodeStatus::ok, src.size()};
      }
      if (dst.size() < out.frame_bytes()) return {DecodeStatus::output_too_small, 0};
      // Stop on warnings too: libjpeg "recovers" from a truncated frame by filling grey, and
      // such a frame must never be published.
      const int rc = tjDecompress2(jpeg, reinterpret_cast<const unsigned char*>(src.data()),
                                   static_cast<unsigned long>(src.size()),
                                   reinterpret_cast<unsigned char*>(dst.data()),
                                   static_cast<int>(out.width), static_cast<int>(out.stride),
                                   static_cast<int>(out.height), tj_format, TJFLAG_STOPONWARNING);
      if (rc != 0) return {DecodeStatus::corrupt_input, 0};
      return {DecodeStatus::ok, out.frame_bytes()};
    }

    if (src.size() < min_input_bytes(in)) return {DecodeStatus::short_input, 0};
    if (method == Method::copy_bytes) {
      const std::uint64_t size = std::min<std::uint64_t>(src.size(), in.frame_bytes());
      if (dst.size() < size) return {DecodeStatus::output_too_small, 0};
      std::memcpy(dst.data(), src.data(), size);
      return {DecodeStatus::ok, size};
    }
    if (dst.size() < out.frame_bytes()) return {DecodeStatus::output_too_small, 0};

    // Headers over the caller's bytes, as consumers get them (sim/opencv.hpp); sizes were checked.
    const cv::Mat source = as_mat(in, src);
    cv::Mat target = as_mat(out, dst);
    if (source.empty() || target.empty()) return {DecodeStatus::failed, 0};
    switch (method) {
      case Method::copy_rows:
        source.copyTo(target);
        break;
      case Method::cvt_color:
        cv::cvtColor(source, target, code);
        break;
      case Method::mono16_to_mono8:
        source.convertTo(target, CV_8U, 1.0 / 256.0);
        break;
      case Method::mono16_to_color:
        source.convertTo(scratch, CV_8U, 1.0 / 256.0);
        cv::cvtColor(scratch, target, code);
        break;
      default:
        return {DecodeStatus::failed, 0};
    }
    // OpenCV reallocates a destination whose size or type does not match; that would mean the
    // frame went to the heap instead of the slot.
    if (target.data != reinterpret_cast<uchar*>(dst.data())) return {DecodeStatus::failed, 0};
    return {DecodeStatus::ok, out.frame_bytes()};
  }
};

Expected<FrameDecoder> FrameDecoder::create(const ImageLayout& input, OutputFormat output) {
  auto impl = std::make_unique<Impl>();
  impl->output = output;
  if (input.width == 0 || input.height == 0 || input.width > 65535 || input.height > 65535) {
    return Error{ErrorCode::invalid_argument,
                 "image size " + std::to_string(input.width) + "x" +
                     std::to_string(input.height) + " is not usable: both must be 1 to 65535"};
  }
  impl->in = make_layout(input.width, input.height, input.format, input.stride);
  if (impl->in.format == PixelFormat::unknown ||
      (impl->in.channels == 0 && !is_compressed(impl->in.format))) {
    return Error{ErrorCode::invalid_argument,
                 std::string("input pixel format ") + sim::to_string(input.format) +
                     " is not supported by the camera decoder"};
  }
  if ((input.format == PixelFormat::yuyv || input.format == PixelFormat::uyvy) &&
      input.width % 2 != 0) {
    return Error{ErrorCode::invalid_argument, "packed 4:2:2 images need an even width"};
  }
  const PixelFormat out_format = output_pixel_format(output, input.format);
  impl->out = output == OutputFormat::raw ? impl->in
                                          : make_layout(input.width, input.height, out_format);
  const bool jpeg = input.format == PixelFormat::mjpeg;
  if (jpeg) {
    impl->jpeg = tjInitDecompress();
    if (impl->jpeg == nullptr) {
      return Error{ErrorCode::system_error, std::string("cannot start the JPEG decoder: ") +
                                                tjGetErrorStr2(nullptr)};
    }
  }
  if (output == OutputFormat::raw) {
    impl->method = jpeg ? Method::jpeg_pass : Method::copy_bytes;
  } else if (jpeg) {
    impl->method = Method::jpeg_decode;
    impl->tj_format = tj_pixel_format(out_format);
  } else if (input.format == out_format) {
    impl->method = Method::copy_rows;
  } else if (input.format == PixelFormat::mono16 && out_format == PixelFormat::mono8) {
    impl->method = Method::mono16_to_mono8;
  } else {
    impl->code = color_code(input.format, out_format);
    if (impl->code < 0) {
      return Error{ErrorCode::invalid_argument,
                   std::string("cannot convert ") + sim::to_string(input.format) + " to " +
                       to_string(output)};
    }
    if (input.format == PixelFormat::mono16) {
      impl->method = Method::mono16_to_color;
      impl->scratch.create(static_cast<int>(input.height), static_cast<int>(input.width), CV_8UC1);
    } else {
      impl->method = Method::cvt_color;
    }
  }
  return FrameDecoder(std::move(impl));
}

FrameDecoder::FrameDecoder(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
FrameDecoder::FrameDecoder(FrameDecoder&&) noexcept = default;
FrameDecoder& FrameDecoder::operator=(FrameDecoder&&) noexcept = default;
FrameDecoder::~FrameDecoder() = default;

const ImageLayout& FrameDecoder::input_layout() const noexcept { return impl_->in; }
const ImageLayout& FrameDecoder::output_layout() const noexcept { return impl_->out; }
OutputFormat FrameDecoder::output() const noexcept { return impl_->output; }

std::uint64_t FrameDecoder::output_capacity(std::uint64_t max_compressed_bytes) const noexcept {
  if (impl_->method == Method::jpeg_pass) return max_compressed_bytes;
  return impl_->out.frame_bytes();
}

DecodeResult FrameDecoder::decode(std::span<const std::byte> in,
                                  std::span<std::byte> out) noexcept {
  try {
    return impl_->decode(in, out);
  } catch (...) {
    // cv::Exception on a frame OpenCV refuses; a status, never an exception, on the hot path.
    return {DecodeStatus::failed, 0};
  }
}

}  // namespace sim::imaging
