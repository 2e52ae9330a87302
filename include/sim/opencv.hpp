// SPDX-License-Identifier: Apache-2.0
// cv::Mat over SIM image frames, header-only so only programs that use OpenCV pay for it:
//   - as_mat(borrow): a zero-copy view of a borrowed frame (valid while borrow.still_valid()),
//   - copy_to(borrow, mat) / read_mat(reader, mat, info): copies for readers who keep frames,
//   - as_mat(loan, layout): a header over the writer's slot, so a driver decodes in place.
// Compressed layouts (MJPEG) have no matrix form: the views come back empty.
#pragma once

#include <cstddef>
#include <opencv2/core/mat.hpp>

#include "sim/layout.hpp"
#include "sim/reader.hpp"
#include "sim/writer.hpp"

namespace sim {

// The cv::Mat element type of an image layout, or -1 when it has none.
inline int cv_type(const ImageLayout& layout) noexcept {
  switch (layout.format) {
    case PixelFormat::mono8:
    case PixelFormat::bayer_rggb8:
    case PixelFormat::bayer_bggr8:
    case PixelFormat::bayer_gbrg8:
    case PixelFormat::bayer_grbg8: return CV_8UC1;
    case PixelFormat::mono16: return CV_16UC1;
    case PixelFormat::bgr8:
    case PixelFormat::rgb8: return CV_8UC3;
    case PixelFormat::bgra8:
    case PixelFormat::rgba8: return CV_8UC4;
    case PixelFormat::yuyv:
    case PixelFormat::uyvy: return CV_8UC2;  // cv::cvtColor's layout for packed 4:2:2
    case PixelFormat::mjpeg:
    case PixelFormat::unknown: break;
  }
  return -1;
}

namespace detail {
inline bool fits(const ImageLayout& layout, std::size_t bytes, int type) noexcept {
  if (type < 0 || layout.width == 0 || layout.height == 0) return false;
  const std::size_t row = std::size_t{layout.width} * CV_ELEM_SIZE(type);
  if (layout.stride < row) return false;
  return bytes >= std::size_t{layout.stride} * (layout.height - 1) + row;
}
}  // namespace detail

// A header over `bytes` laid out as `layout`; empty when the layout has no matrix form or the
// bytes are too few. No copy: the matrix lives as long as the bytes.
inline cv::Mat as_mat(const ImageLayout& layout, span<std::byte> bytes) {
  const int type = cv_type(layout);
  if (!detail::fits(layout, bytes.size(), type)) return {};
  return cv::Mat(static_cast<int>(layout.height), static_cast<int>(layout.width), type,
                 bytes.data(), layout.stride);
}

// Read-only view. cv::Mat has no const element type: writing through it is undefined behaviour
// on a reader's mapping (which is read-only and would fault).
inline cv::Mat as_mat(const ImageLayout& layout, span<const std::byte> bytes) {
  return as_mat(layout, span<std::byte>(const_cast<std::byte*>(bytes.data()), bytes.size()));
}

// Zero-copy view of a borrowed frame. Check borrow.still_valid() after using the pixels.
inline cv::Mat as_mat(const Borrow& borrow) {
  if (borrow.status() != ReadStatus::new_frame ||
      borrow.info().layout.kind != LayoutKind::image) {
    return {};
  }
  return as_mat(borrow.info().layout.image, borrow.bytes());
}

// A header over the writer's back slot: decode into it, then loan.commit(frame_bytes, stamp).
inline cv::Mat as_mat(const Loan& loan, const ImageLayout& layout) {
  return as_mat(layout, loan.bytes());
}

// Copies a borrowed frame out. False when there was nothing to copy or the writer overwrote
// the slot during the copy (then `out` must be discarded).
inline bool copy_to(const Borrow& borrow, cv::Mat& out) {
  const cv::Mat view = as_mat(borrow);
  if (view.empty()) return false;
  view.copyTo(out);
  return borrow.still_valid();
}

// Reads the newest frame into `out` (reallocated only when the size or type changes); rows
// keep the stream's stride, so a padded raw stream is a column range of a wider matrix.
inline ReadStatus read_mat(Reader& reader, cv::Mat& out, FrameInfo& info) {
  const Layout& layout = reader.layout();
  const int type = cv_type(layout.image);
  if (layout.kind != LayoutKind::image || type < 0 ||
      layout.image.stride % CV_ELEM_SIZE(type) != 0) {
    return ReadStatus::buffer_too_small;
  }
  const auto rows = static_cast<int>(layout.image.height);
  const auto step_cols = static_cast<int>(layout.image.stride / CV_ELEM_SIZE(type));
  const std::size_t needed = std::size_t{layout.image.stride} * layout.image.height;
  const bool reusable = out.data != nullptr && out.rows == rows &&
                        out.cols == static_cast<int>(layout.image.width) && out.type() == type &&
                        out.step[0] == layout.image.stride &&
                        static_cast<std::size_t>(out.datalimit - out.data) >= needed;
  cv::Mat full;
  if (reusable) {
    full = cv::Mat(rows, step_cols, type, out.data, layout.image.stride);
  } else {
    full.create(rows, step_cols, type);
    out = full.colRange(0, static_cast<int>(layout.image.width));
  }
  return reader.read(span<std::byte>(reinterpret_cast<std::byte*>(full.data),
                                          full.total() * full.elemSize()),
                     info);
}

}  // namespace sim
