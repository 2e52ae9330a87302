// SPDX-License-Identifier: Apache-2.0
// One decoder for every camera source: it turns one frame in its device format (YUYV, UYVY,
// MJPEG, grey, Bayer, BGR from a video file) into the published format, writing straight into
// the caller's buffer, which is normally the writer's loaned slot in shared memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "sim/imaging/image_format.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::imaging {

enum class DecodeStatus : std::uint8_t {
  ok,
  short_input,       // fewer bytes than one frame of the input layout: a truncated buffer
  corrupt_input,     // the compressed data does not decode cleanly (corrupt or truncated JPEG)
  wrong_size,        // the compressed image's width/height differ from the negotiated ones
  output_too_small,  // the destination cannot hold the decoded frame
  failed,            // the conversion library refused the frame (should not happen)
};

const char* to_string(DecodeStatus status) noexcept;

struct DecodeResult {
  DecodeStatus status = DecodeStatus::failed;
  std::uint64_t size = 0;  // bytes written to the destination when status is ok
};

class FrameDecoder {
 public:
  // `input` describes the source frames (for MJPEG: the expected width and height, stride 0).
  // Fails with one sentence when the conversion is not supported.
  static Expected<FrameDecoder> create(const ImageLayout& input, OutputFormat output);

  FrameDecoder(FrameDecoder&&) noexcept;
  FrameDecoder& operator=(FrameDecoder&&) noexcept;
  FrameDecoder(const FrameDecoder&) = delete;
  FrameDecoder& operator=(const FrameDecoder&) = delete;
  ~FrameDecoder();

  const ImageLayout& input_layout() const noexcept;
  const ImageLayout& output_layout() const noexcept;
  OutputFormat output() const noexcept;
  // Slot capacity needed for one output frame; for MJPEG passed through raw it is
  // `max_compressed_bytes`, the largest frame the source announces (V4L2 sizeimage).
  std::uint64_t output_capacity(std::uint64_t max_compressed_bytes) const noexcept;

  // Decodes one frame. Nothing is allocated; on any status but ok the destination holds garbage
  // and must not be published.
  DecodeResult decode(std::span<const std::byte> in, std::span<std::byte> out) noexcept;

 private:
  struct Impl;
  explicit FrameDecoder(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::imaging
