// SPDX-License-Identifier: Apache-2.0
// Test-only: the one accept loop of every fake sensor the LiDAR tests talk TCP to (Hesai's PTC,
// Ouster's HTTP API). A real listening socket on 127.0.0.1, port 0 (the kernel picks a free one),
// and a thread that hands each connection to the test's handler until the server is destroyed.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace lidar_test {

// What the server does with a connection once the handler has answered.
enum class AfterAnswer {
  close,  // the sensor closes (HTTP/1.0, a PTC answer)
  hold,   // kept open and silent until the server is destroyed (a stalled sensor)
};

// Writes all of `bytes` unless the peer goes away.
inline void send_all(int fd, const std::string& bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return;
    sent += static_cast<std::size_t>(n);
  }
}

class FakeTcpServer {
 public:
  using Handler = std::function<AfterAnswer(int fd)>;

  // The handler runs on the server's thread, one connection at a time.
  explicit FakeTcpServer(Handler handler)
      : handler_(std::move(handler)), listener_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(listener_, reinterpret_cast<const sockaddr*>(&address), sizeof address);
    ::listen(listener_, 8);
    socklen_t length = sizeof address;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  FakeTcpServer(const FakeTcpServer&) = delete;
  FakeTcpServer& operator=(const FakeTcpServer&) = delete;
  ~FakeTcpServer() {
    stop_ = true;
    thread_.join();
    for (int fd : held_) ::close(fd);
    ::close(listener_);
  }

  std::uint16_t port() const { return port_; }

 private:
  void serve() {
    while (!stop_) {
      pollfd p{listener_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;  // 20 ms: how soon the destructor is noticed
      const int fd = ::accept(listener_, nullptr, nullptr);
      if (fd < 0) continue;
      if (handler_(fd) == AfterAnswer::hold) {
        held_.push_back(fd);
      } else {
        ::close(fd);
      }
    }
  }

  Handler handler_;
  int listener_;
  std::uint16_t port_ = 0;
  std::vector<int> held_;  // only touched by the server thread until it is joined
  std::atomic<bool> stop_{false};
  std::thread thread_;  // last: it starts once every member above exists
};

// A loopback port nothing listens on: bound once to learn a free number, then closed.
inline std::uint16_t closed_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address);
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(fd);
  return ntohs(address.sin_port);
}

}  // namespace lidar_test
