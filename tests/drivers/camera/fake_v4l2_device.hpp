// SPDX-License-Identifier: Apache-2.0
// An in-memory V4L2 capture device behind the driver's system-call seam. It keeps the state a
// kernel driver keeps (format, buffers and their queue, streaming, controls) and answers the
// ioctls the driver uses, with the kernel's error codes. Tests script what the "camera" does:
// frames in any format and size, EAGAIN, device errors, sequence gaps, unplug and replug.
#pragma once

#include <linux/videodev2.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "sim/camera/v4l2_device.hpp"
#include "sim/camera/v4l2_io.hpp"

namespace sim::camera::testing {

struct FakeFormat {
  FourCc fourcc;
  std::string description;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> sizes;  // discrete width × height
  std::vector<std::uint32_t> fps = {30, 15};
};

struct FakeControl {
  std::uint32_t id = 0;
  std::string name;
  std::uint32_t type = 1;  // V4L2_CTRL_TYPE_INTEGER
  std::int32_t minimum = 0;
  std::int32_t maximum = 255;
  std::int32_t step = 1;
  std::int32_t default_value = 128;
  std::int32_t value = 128;
  std::vector<std::string> menu;  // for V4L2_CTRL_TYPE_MENU
};

struct FakeFrame {
  std::vector<std::byte> bytes;       // bytesused; longer than the buffer is cut to the buffer
  std::uint32_t sequence_gap = 0;     // frames the "device" lost before this one
  bool error_flag = false;            // V4L2_BUF_FLAG_ERROR
  std::int64_t timestamp_ns = -1;     // -1: CLOCK_MONOTONIC now
  // The buffer's clock and stamp point (V4L2_BUF_FLAG_TIMESTAMP_*, V4L2_BUF_FLAG_TSTAMP_SRC_*).
  std::uint32_t timestamp_flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
};

class FakeV4l2Device final : public V4l2Io {
 public:
  FakeV4l2Device(std::string path, std::vector<FakeFormat> formats,
                 std::vector<FakeControl> controls = {});
  ~FakeV4l2Device() override;

  // What the camera does next, in order.
  void push_frame(FakeFrame frame);
  void push_error(int error);  // the next DQBUF fails with this errno
  void push_stall();           // one poll() that times out
  // Unplug: every open handle fails with ENODEV and poll reports POLLERR; open fails with
  // ENOENT until plug().
  void unplug();
  void plug();
  // Padding bytes the "driver" adds to each row (bytesperline > width × bytes per pixel).
  void set_row_padding(std::uint32_t bytes) { row_padding_ = bytes; }

  std::size_t pending() const { return events_.size(); }
  bool streaming() const { return streaming_; }
  int open_handles() const { return static_cast<int>(fds_.size()); }
  int mapped_buffers() const { return mapped_; }
  std::uint32_t buffer_count() const { return static_cast<std::uint32_t>(buffers_.size()); }
  std::uint32_t queued_buffers() const { return static_cast<std::uint32_t>(queue_.size()); }
  FourCc fourcc() const { return FourCc{pixelformat_}; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  std::uint32_t bytes_per_line() const;
  std::uint32_t size_image() const;
  std::uint32_t fps() const { return fps_; }
  std::int32_t control(std::uint32_t id) const;
  int opens() const { return opens_; }

  // V4l2Io
  int open(const char* path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(std::size_t length, int prot, int flags, int fd, std::int64_t offset) override;
  int munmap(void* address, std::size_t length) override;
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override;

 private:
  struct Stall {};
  using Event = std::variant<FakeFrame, int, Stall>;
  struct Buffer {
    std::unique_ptr<std::byte[]> memory;
    std::size_t length = 0;
    bool queued = false;
  };
  const FakeFormat* find(std::uint32_t fourcc) const;
  int fail(int error) const;
  void free_buffers();
  // One handler per ioctl request (arg is that request's structure).
  int query_capabilities(void* arg);
  int enumerate_format(void* arg);
  int enumerate_frame_size(void* arg);
  int enumerate_frame_interval(void* arg);
  int get_format(void* arg);
  int try_or_set_format(void* arg, bool set);
  int stream_parameters(void* arg, bool set);
  int query_control(void* arg);
  int query_menu(void* arg);
  int get_or_set_control(void* arg, bool set);
  int request_buffers(void* arg);
  int query_buffer(void* arg);
  int queue_buffer(void* arg);
  int dequeue(void* arg);
  int stream_on();
  int stream_off();

  std::string path_;
  std::vector<FakeFormat> formats_;
  std::vector<FakeControl> controls_;
  std::deque<Event> events_;
  std::set<int> fds_;
  int next_fd_ = 100;
  int opens_ = 0;
  bool unplugged_ = false;
  std::uint32_t pixelformat_ = 0;
  std::uint32_t width_ = 0;
  std::uint32_t height_ = 0;
  std::uint32_t fps_ = 30;
  std::uint32_t row_padding_ = 0;
  std::vector<Buffer> buffers_;
  std::vector<std::unique_ptr<std::byte[]>> retired_;  // kept while a lost handle may map them
  std::deque<std::uint32_t> queue_;
  std::uint32_t sequence_ = 0;
  bool streaming_ = false;
  int mapped_ = 0;
};

}  // namespace sim::camera::testing
