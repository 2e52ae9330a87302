// SPDX-License-Identifier: Apache-2.0
// TcpConnection: a short TCP exchange with a sensor's service (the Hesai PTC calibration, the
// Ouster HTTP metadata) where every step ends by one deadline, so a sensor that does not
// answer, or stops answering halfway, costs at most the timeout and never hangs the driver.
//
//   auto connection = sim::lidar::TcpConnection::connect({"192.168.1.201", 9347, 3s, "PTC"});
//   if (!connection) -> connection.error().message ("sensor 192.168.1.201:9347 refused …")
//   connection->send_all(request) == TcpIo::done
//   connection->read_some(buffer) -> {TcpIo::done, n} or closed / timed_out / failed
//
// The sensor's fetched file is kept for the next start: default_cache_path, write_atomically.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "sim/result.hpp"

namespace sim::lidar {

struct TcpPeer {
  std::string host;                         // an IPv4/IPv6 address, or a name (os-122.local)
  std::uint16_t port = 0;
  std::chrono::milliseconds timeout{3000};  // for the whole exchange, from connect()
  std::string service = "TCP";              // names the connection in messages: "the PTC connection"
};

enum class TcpIo {
  done,       // sent all; read some bytes
  closed,     // the sensor closed the connection
  timed_out,  // the deadline passed first
  failed,     // the connection broke (TcpRead::error says how)
};

struct TcpRead {
  TcpIo status = TcpIo::done;
  std::size_t size = 0;  // bytes read, with done
  int error = 0;         // errno, with failed
};

// Empty when `host` can name a sensor for TcpPeer: an IPv4 or IPv6 address, or a name of
// letters, digits, dots and dashes (resolved when connecting); else why not, as "'x' is …".
std::string host_problem(const std::string& host);

class TcpConnection {
 public:
  // Resolves the host and connects to its first address before the deadline (now + timeout):
  // a name that does not resolve in time uses up the same timeout. Errors, one sentence naming
  // the sensor: invalid_argument for a host that is neither an address nor a known name,
  // system_error when the name does not resolve in time, or the sensor refuses the connection or
  // does not accept it in time.
  static Expected<TcpConnection> connect(const TcpPeer& peer);

  TcpConnection(TcpConnection&& other) noexcept;
  TcpConnection& operator=(TcpConnection&& other) noexcept;
  TcpConnection(const TcpConnection&) = delete;
  TcpConnection& operator=(const TcpConnection&) = delete;
  ~TcpConnection();

  // Sends every byte before the deadline: done, closed or timed_out.
  TcpIo send_all(std::span<const std::uint8_t> bytes) noexcept;
  // Reads what has arrived (at most buffer.size() bytes), waiting for it until the deadline.
  TcpRead read_some(std::span<std::uint8_t> buffer) noexcept;

  const std::string& who() const noexcept;  // "sensor 192.168.1.201:9347", for messages
  const std::string& within() const noexcept;  // "within 3 s", for messages

 private:
  TcpConnection(int fd, std::int64_t deadline_ns, std::string who, std::string within) noexcept;
  int fd_ = -1;
  std::int64_t deadline_ns_ = 0;  // CLOCK_MONOTONIC
  std::string who_;
  std::string within_;
};

// Where the file fetched from a sensor is cached when no path is named:
// $XDG_CACHE_HOME/sim/<file_name>, else ~/.cache/sim/<file_name>.
std::filesystem::path default_cache_path(const std::string& file_name);

// Writes `text` to `path` through a temporary file and a rename (a reader never sees half a
// file), creating its folder. False when that failed (nothing is left behind).
bool write_atomically(const std::filesystem::path& path, std::string_view text);

}  // namespace sim::lidar
