// SPDX-License-Identifier: Apache-2.0
// One open V4L2 capture device: what it offers (formats, sizes, rates, controls), format
// negotiation, and mmap streaming driven by poll(). It knows nothing about SIM streams; the
// capture loop (v4l2_capture.hpp) puts it together with the decoder and the writer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sim/imaging/image_format.hpp"
#include "sim/camera/v4l2_io.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"

namespace sim::camera {

// A V4L2 pixel format code ("YUYV", "MJPG", …).
struct FourCc {
  std::uint32_t code = 0;

  static constexpr FourCc of(char a, char b, char c, char d) noexcept {
    return {static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
            static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8 |
            static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16 |
            static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24};
  }
  // Four characters, case-sensitive as V4L2 spells them; "MJPEG" is accepted for "MJPG".
  static std::optional<FourCc> parse(std::string_view text) noexcept;
  std::string str() const;
  friend bool operator==(FourCc, FourCc) = default;
};

// The SIM pixel format of a V4L2 format, or unknown when SIM cannot decode it.
PixelFormat pixel_format_of(FourCc fourcc) noexcept;

struct FrameSizeInfo {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<double> fps;  // discrete rates the device offers at this size (may be empty)
};

struct FormatInfo {
  FourCc fourcc;
  std::string description;
  bool compressed = false;
  std::vector<FrameSizeInfo> sizes;  // discrete sizes; for stepwise devices the min and the max
};

struct ControlInfo {
  std::uint32_t id = 0;
  std::string name;  // as the driver spells it: "Exposure Time, Absolute"
  std::string key;   // the --ctrl name: lower case, other characters as '_': "exposure_time_absolute"
  std::uint32_t type = 0;  // V4L2_CTRL_TYPE_*
  std::int32_t minimum = 0;
  std::int32_t maximum = 0;
  std::int32_t step = 0;
  std::int32_t default_value = 0;
  std::int32_t value = 0;
  bool read_only = false;
  std::vector<std::pair<std::int32_t, std::string>> menu;  // menu controls: index → name
};

// The lower-case key V4L2 control names are matched by.
std::string control_key(std::string_view name);

struct FormatRequest {
  std::optional<FourCc> fourcc;  // empty: choose automatically for the output
  std::uint32_t width = 0;       // 0: keep the device's current size
  std::uint32_t height = 0;
  double fps = 0;                // 0: keep the device's current rate
  imaging::OutputFormat output = imaging::OutputFormat::bgr8;
};

struct StreamFormat {
  FourCc fourcc;
  ImageLayout layout;           // the device's frames (stride = bytesperline)
  std::uint32_t size_image = 0; // the largest buffer the device fills (bounds MJPEG frames)
  double fps = 0;               // 0 when the device does not report it
};

// Which clock the driver stamped a buffer with (V4L2_BUF_FLAG_TIMESTAMP_*).
enum class BufferClock : std::uint8_t {
  unknown,    // TIMESTAMP_UNKNOWN (or a value V4L2 does not define)
  monotonic,  // TIMESTAMP_MONOTONIC: the host's CLOCK_MONOTONIC
  copy,       // TIMESTAMP_COPY: copied from the output buffer (a memory-to-memory device)
};
const char* to_string(BufferClock clock) noexcept;  // "unknown", "monotonic", "copy"

// When in the frame the stamp was taken (V4L2_BUF_FLAG_TSTAMP_SRC_*).
enum class StampPoint : std::uint8_t {
  end_of_frame,       // TSTAMP_SRC_EOF: the last pixel (the kernel's default)
  start_of_exposure,  // TSTAMP_SRC_SOE
};

// A buffer's flags as the two above.
BufferClock buffer_clock(std::uint32_t flags) noexcept;
StampPoint stamp_point(std::uint32_t flags) noexcept;

struct DeviceFrame {
  std::uint32_t index = 0;
  std::span<const std::byte> bytes;  // bytesused bytes of the mmap'ed buffer
  std::uint32_t sequence = 0;
  std::int64_t timestamp_ns = 0;
  BufferClock clock = BufferClock::unknown;
  StampPoint stamp_point = StampPoint::end_of_frame;
  bool error = false;                // V4L2_BUF_FLAG_ERROR: the device says the data is bad
};

enum class WaitResult : std::uint8_t {
  frame,        // `frame` holds a dequeued buffer: give it back with requeue()
  timeout,      // nothing within the timeout
  again,        // woken, but no buffer yet (EAGAIN, EINTR)
  device_lost,  // ENODEV, EIO, POLLERR: unplugged or dead; close and reopen
};

class V4l2Device {
 public:
  // Opens a capture device; one sentence on failure (missing node, not a camera, no streaming).
  static Expected<V4l2Device> open(V4l2Io& io, const std::string& path);

  V4l2Device(V4l2Device&& other) noexcept;
  V4l2Device& operator=(V4l2Device&& other) noexcept;
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;
  ~V4l2Device();

  const std::string& path() const noexcept { return path_; }
  const std::string& card() const noexcept { return card_; }
  // Where the device is plugged (VIDIOC_QUERYCAP bus_info: "usb-0000:00:14.0-1").
  const std::string& bus() const noexcept { return bus_; }

  std::vector<FormatInfo> formats();
  std::vector<ControlInfo> controls();
  // Sets a control by key: integers, true/false for booleans, an index or a name for menus.
  std::optional<Error> set_control(std::string_view key, std::string_view value);

  // Chooses and sets the format, size and rate closest to the request the device accepts.
  Expected<StreamFormat> negotiate(const FormatRequest& request);

  // Allocates and maps `buffer_count` buffers, queues them and starts streaming.
  std::optional<Error> start(std::uint32_t buffer_count);
  // poll() then VIDIOC_DQBUF.
  WaitResult wait(int timeout_ms, DeviceFrame& frame);
  // Gives a dequeued buffer back to the device.
  WaitResult requeue(const DeviceFrame& frame);
  // Stops streaming and unmaps the buffers; safe on a lost device.
  void stop() noexcept;

 private:
  struct Buffer {
    void* address = nullptr;
    std::size_t length = 0;
  };
  V4l2Device(V4l2Io& io, int fd, std::string path, std::string card) noexcept;
  int xioctl(unsigned long request, void* arg);
  std::vector<FrameSizeInfo> frame_sizes(std::uint32_t fourcc);
  std::vector<double> frame_rates(std::uint32_t fourcc, std::uint32_t width, std::uint32_t height);
  void close() noexcept;

  V4l2Io* io_ = nullptr;
  int fd_ = -1;
  std::string path_;
  std::string card_;
  std::string bus_;
  std::vector<Buffer> buffers_;
  bool buffers_requested_ = false;  // REQBUFS succeeded: give them back with a count of 0
  bool streaming_ = false;
};

}  // namespace sim::camera
