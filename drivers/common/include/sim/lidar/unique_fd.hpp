// SPDX-License-Identifier: Apache-2.0
// UniqueFd: one open file descriptor, closed when its owner goes (the receivers' sockets and
// serial ports). Move-only; -1 owns nothing.
#pragma once

#include <unistd.h>

#include <utility>

namespace sim::lidar {

class UniqueFd {
 public:
  explicit UniqueFd(int fd = -1) noexcept : fd_(fd) {}
  UniqueFd(UniqueFd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept {
    std::swap(fd_, other.fd_);
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const noexcept { return fd_; }

 private:
  int fd_;
};

}  // namespace sim::lidar
