// SPDX-License-Identifier: Apache-2.0
// A small fake sensor HTTP API for tests (Ouster's /api/v1/…): HTTP/1.0 on the shared accept
// loop (fake_tcp_server.hpp), closing after each answer as the sensor does.
#pragma once

#include <sys/socket.h>

#include <atomic>
#include <map>
#include <mutex>
#include <string>
#include <utility>

#include "lidar_test/fake_tcp_server.hpp"

namespace lidar_test {

// A sensor's HTTP API on 127.0.0.1 (port 0): answers GET /api/v1/sensor/metadata with `body`,
// and any other path the test routes (set_route: a status and a body, changeable while it runs);
// everything else is 404.
class FakeSensorHttp {
 public:
  explicit FakeSensorHttp(std::string body) : body_(std::move(body)) {}
  std::uint16_t port() const { return server_.port(); }
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
  AfterAnswer answer(int fd) {
    std::string request;
    char chunk[1024];
    while (request.find("\r\n\r\n") == std::string::npos) {
      const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
      if (n <= 0) break;
      request.append(chunk, static_cast<std::size_t>(n));
    }
    ++requests_;
    send_all(fd, answer_to(request));
    return AfterAnswer::close;
  }

  std::string answer_to(const std::string& request) {
    // "GET <path> HTTP/1.x"
    std::string path;
    if (request.rfind("GET ", 0) == 0) path = request.substr(4, request.find(' ', 4) - 4);
    std::lock_guard lock(mutex_);
    ++asked_[path];
    const auto routed = routes_.find(path);
    if (routed != routes_.end()) {
      const int status = routed->second.first;
      return "HTTP/1.0 " + std::to_string(status) + (status == 200 ? " OK" : " Not Found") +
             "\r\nContent-Type: application/json\r\n\r\n" + routed->second.second;
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
  std::atomic<int> requests_{0};
  FakeTcpServer server_{[this](int fd) { return answer(fd); }};  // last: it serves the members above
};

}  // namespace lidar_test
