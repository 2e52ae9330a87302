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

// The lowest --max-rate: one message per ~11 days. Lower rates are refused (their interval
// would not fit a 64-bit nanosecond count).
inline constexpr double kMinRateHz = 1e-6;

struct ServerOptions {
  std::string bind = "127.0.0.1";  // loopback unless told otherwise
  std::uint16_t port = 8765;       // 0 picks a free port (see Server::port())
  std::vector<std::string> streams;  // only these streams; empty: every stream
  double max_rate_hz = 0;  // per client and channel; 0: as fast as frames come; else >= kMinRateHz
  bool compress_jpeg = false;        // images as sensor_msgs/msg/CompressedImage (JPEG)
  int jpeg_quality = 80;             // 1–100, for --compress jpeg and the page's images
  std::chrono::milliseconds poll_interval{500};  // how often new and removed streams are found
  std::chrono::milliseconds send_timeout{10'000};  // a client that takes no data this long is closed
  // Connections served at once (page and Foxglove together); more get 503 and one sentence.
  // Lowered further when the process may not open this many descriptors (RLIMIT_NOFILE).
  unsigned max_connections = 256;
  // Web origins besides this server's own page whose scripts may open the WebSocket (the
  // Foxglove web app's are allowed by default), e.g. "https://viewer.example"; "*" allows any.
  // Their host names are also accepted in HTTP Host headers (against DNS rebinding).
  std::vector<std::string> allowed_origins;
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
  // How often accepting a connection failed (out of descriptors, …); each failure waits before
  // the next try instead of spinning. For tests and diagnostics.
  std::uint64_t accept_failures() const noexcept;
  // Stops accepting, closes every connection and joins every thread. Idempotent.
  void stop();

  struct Impl;

 private:
  explicit Server(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::foxglove
