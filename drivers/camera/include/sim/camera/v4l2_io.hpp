// SPDX-License-Identifier: Apache-2.0
// The system-call boundary under the V4L2 driver. Everything above it (negotiation, streaming,
// timestamps, reconnect, decoding) is tested against an in-memory fake device, because this
// project's kernels have no V4L2 at all; real cameras go through libv4l2.
// Calls follow the system calls they stand for: -1 (or MAP_FAILED) and errno on failure.
#pragma once

#include <poll.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace sim::camera {

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;
  virtual int open(const char* path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* mmap(std::size_t length, int prot, int flags, int fd, std::int64_t offset) = 0;
  virtual int munmap(void* address, std::size_t length) = 0;
  virtual int poll(pollfd* fds, nfds_t count, int timeout_ms) = 0;
};

// Real devices through libv4l2 with its format conversion disabled: SIM decodes frames itself,
// straight into shared memory, instead of letting libv4l2 convert into a buffer of its own.
std::unique_ptr<V4l2Io> make_libv4l2_io();

}  // namespace sim::camera
