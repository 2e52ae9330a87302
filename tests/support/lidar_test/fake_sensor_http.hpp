// SPDX-License-Identifier: Apache-2.0
// A small fake Ouster sensor's HTTP API for tests: a real TCP server on loopback (port 0),
// HTTP/1.0 (it closes after each answer, as the sensor does).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace ouster_test {

// A sensor's HTTP API on 127.0.0.1 (port 0): answers GET /api/v1/sensor/metadata with `body`,
// and any other path the test routes (set_route: a status and a body, changeable while it runs);
// everything else is 404.
class FakeSensorHttp {
 public:
  explicit FakeSensorHttp(std::string body) : body_(std::move(body)), listener_(::socket(AF_INET, SOCK_STREAM, 0)) {
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
  ~FakeSensorHttp() {
    stop_ = true;
    thread_.join();
    ::close(listener_);
  }
  std::uint16_t port() const { return port_; }
  int requests() const { return requests_; }
  // GET `path` answers `status` with `body` from now on (status 0: the route is removed).
  void set_route(const std::string& path, int status, std::string body) {
    std::lock_guard lock(mutex_);
    if (status == 0) {
      routes_.erase(path);
    } else {
      routes_[path] = {status, std::move(body)};
    }
  }
  int requests_for(const std::string& path) const {
    std::lock_guard lock(mutex_);
    const auto found = asked_.find(path);
    return found == asked_.end() ? 0 : found->second;
  }

 private:
  void serve() {
    while (!stop_) {
      pollfd p{listener_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      const int fd = ::accept(listener_, nullptr, nullptr);
      if (fd < 0) continue;
      std::string request;
      char chunk[1024];
      while (request.find("\r\n\r\n") == std::string::npos) {
        const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
        if (n <= 0) break;
        request.append(chunk, static_cast<std::size_t>(n));
      }
      ++requests_;
      const std::string answer = answer_to(request);
      (void)::send(fd, answer.data(), answer.size(), MSG_NOSIGNAL);
      ::close(fd);
    }
  }

  std::string answer_to(const std::string& request) {
    // "GET <path> HTTP/1.x"
    std::string path;
    if (request.rfind("GET ", 0) == 0) path = request.substr(4, request.find(' ', 4) - 4);
    std::lock_guard lock(mutex_);
    ++asked_[path];
    const auto routed = routes_.find(path);
    if (routed != routes_.end()) {
      const auto& [status, body] = routed->second;
      return "HTTP/1.0 " + std::to_string(status) + (status == 200 ? " OK" : " Not Found") +
             "\r\nContent-Type: application/json\r\n\r\n" + body;
    }
    if (path == "/api/v1/sensor/metadata") {
      return "HTTP/1.0 200 OK\r\nContent-Type: application/json\r\n\r\n" + body_;
    }
    return "HTTP/1.0 404 Not Found\r\n\r\n";
  }

  std::string body_;
  mutable std::mutex mutex_;
  std::map<std::string, std::pair<int, std::string>> routes_;
  std::map<std::string, int> asked_;
  int listener_;
  std::uint16_t port_ = 0;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> requests_{0};
};

}  // namespace ouster_test
