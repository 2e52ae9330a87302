// SPDX-License-Identifier: Apache-2.0
#include <fcntl.h>
#include <libv4l2.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

#include "sim/camera/v4l2_io.hpp"

namespace sim::camera {

namespace {

class LibV4l2Io final : public V4l2Io {
 public:
  int open(const char* path, int flags) override {
    const int fd = ::open(path, flags | O_CLOEXEC);
    if (fd < 0) return -1;
    // v4l2_open() would enable libv4l2's software conversion; we want the device's own formats.
    if (v4l2_fd_open(fd, V4L2_DISABLE_CONVERSION) < 0) {
      const int saved = errno;
      ::close(fd);
      errno = saved;
      return -1;
    }
    return fd;
  }
  int close(int fd) override { return v4l2_close(fd); }
  int ioctl(int fd, unsigned long request, void* arg) override {
    return v4l2_ioctl(fd, request, arg);
  }
  void* mmap(std::size_t length, int prot, int flags, int fd, std::int64_t offset) override {
    return v4l2_mmap(nullptr, length, prot, flags, fd, offset);
  }
  int munmap(void* address, std::size_t length) override { return v4l2_munmap(address, length); }
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override {
    return ::poll(fds, count, timeout_ms);
  }
};

}  // namespace

std::unique_ptr<V4l2Io> make_libv4l2_io() { return std::make_unique<LibV4l2Io>(); }

}  // namespace sim::camera
