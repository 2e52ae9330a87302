// SPDX-License-Identifier: Apache-2.0
// sim_foxglove's server: every SIM stream on this machine as a channel of the Foxglove WebSocket
// protocol (foxglove.websocket.v1, CDR-encoded ROS 2 messages), plus a built-in page on the same
// port (plain HTTP GET) that shows every stream's health, the newest camera images and a top-down
// view of the newest LiDAR frames. See docs/foxglove.md.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/reader.hpp"
#include "sim/result.hpp"

namespace sim::foxglove {

struct ServerOptions {
  std::string bind = "127.0.0.1";  // loopback unless told otherwise
  std::uint16_t port = 8765;       // 0 picks a free port (see Server::port())
  std::vector<std::string> streams;  // only these streams; empty: every stream
  double max_rate_hz = 0;            // per client and channel; 0: as fast as frames come
  bool compress_jpeg = false;        // images as sensor_msgs/msg/CompressedImage (JPEG)
  int jpeg_quality = 80;             // 1–100, for --compress jpeg and the page's images
  std::chrono::milliseconds poll_interval{500};  // how often new and removed streams are found
  std::chrono::milliseconds send_timeout{10'000};  // a client that takes no data this long is closed
  unsigned io_threads = 2;
  std::string name = "sim_foxglove";
  Trust trust{};  // whose regions to serve (--trust-owner, --trust-group); default: this user's
};

// The running server: bound and serving once start() returns; stops when destroyed.
class Server {
 public:
  static Expected<Server> start(const ServerOptions& options);

  Server(Server&&) noexcept;
  Server& operator=(Server&&) noexcept;
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;
  ~Server();

  std::uint16_t port() const noexcept;
  // Stops accepting, closes every connection and joins every thread. Idempotent.
  void stop();

  struct Impl;

 private:
  explicit Server(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::foxglove
