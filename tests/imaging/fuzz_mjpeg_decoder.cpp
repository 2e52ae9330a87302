// SPDX-License-Identifier: Apache-2.0
// Outside bytes into the MJPEG decoder (decode into a slot and pass-through): whatever a camera
// or a video file sends, the decoder must return a status and stay inside the slot.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/imaging/decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sim;
  static auto decode = imaging::FrameDecoder::create(imaging::make_layout(64, 48, sim::PixelFormat::mjpeg),
                                            imaging::OutputFormat::bgr8);
  static auto pass = imaging::FrameDecoder::create(imaging::make_layout(64, 48, sim::PixelFormat::mjpeg),
                                          imaging::OutputFormat::raw);
  static std::vector<std::byte> slot(64 * 48 * 3);
  const std::span<const std::byte> input(reinterpret_cast<const std::byte*>(data), size);
  const imaging::DecodeResult decoded = decode->decode(input, slot);
  if (decoded.status == imaging::DecodeStatus::ok && decoded.size != slot.size()) __builtin_trap();
  const imaging::DecodeResult passed = pass->decode(input, slot);
  if (passed.status == imaging::DecodeStatus::ok && passed.size != size) __builtin_trap();
  return 0;
}
