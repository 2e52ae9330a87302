// SPDX-License-Identifier: Apache-2.0
#include "sim/lidar/tcp_client.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <system_error>
#include <utility>

#include "sim/clock.hpp"

namespace sim::lidar {
namespace {

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

// Waits for `events` on `fd` until `deadline_ns` (monotonic): true when ready.
bool wait_for(int fd, short events, std::int64_t deadline_ns) {
  for (;;) {
    const std::int64_t left_ms = (deadline_ns - monotonic_ns()) / 1'000'000;
    if (left_ms <= 0) return false;
    pollfd p{fd, events, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min<std::int64_t>(left_ms, 1000)));
    if (r > 0) return true;
    if (r < 0 && errno != EINTR) return false;
  }
}

// "3 s", "0.4 s".
std::string seconds_text(std::chrono::milliseconds timeout) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", static_cast<double>(timeout.count()) / 1000.0);
  return text;
}

}  // namespace

Expected<TcpConnection> TcpConnection::connect(const TcpPeer& peer) {
  const std::int64_t deadline = monotonic_ns() + peer.timeout.count() * 1'000'000;
  std::string who = "sensor " + peer.host + ":" + std::to_string(peer.port);
  std::string within = "within " + seconds_text(peer.timeout);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(peer.port);
  if (::inet_pton(AF_INET, peer.host.c_str(), &address.sin_addr) != 1) {
    return Error{ErrorCode::invalid_argument,
                 "--sensor-ip '" + peer.host + "' is not an IPv4 address (e.g. 192.168.1.201)"};
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return failed("cannot open a TCP socket: " + std::string(std::strerror(errno)));
  TcpConnection connection(fd, deadline, std::move(who), std::move(within));
  const std::string refused = connection.who_ + " refused the " + peer.service + " connection (";
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) return connection;
  if (errno != EINPROGRESS) {
    return failed(refused + std::strerror(errno) + "); check --sensor-ip and that the sensor is on");
  }
  if (!wait_for(fd, POLLOUT, deadline)) {
    return failed(connection.who_ + " did not accept the " + peer.service + " connection " +
                  connection.within_ + "; check --sensor-ip and the network");
  }
  int error = 0;
  socklen_t length = sizeof error;
  ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
  if (error != 0) {
    return failed(refused + std::strerror(error) + "); check --sensor-ip and that the sensor is on");
  }
  return connection;
}

TcpConnection::TcpConnection(int fd, std::int64_t deadline_ns, std::string who, std::string within) noexcept
    : fd_(fd), deadline_ns_(deadline_ns), who_(std::move(who)), within_(std::move(within)) {}

TcpConnection::TcpConnection(TcpConnection&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), deadline_ns_(other.deadline_ns_), who_(std::move(other.who_)),
      within_(std::move(other.within_)) {}

TcpConnection& TcpConnection::operator=(TcpConnection&& other) noexcept {
  std::swap(fd_, other.fd_);
  deadline_ns_ = other.deadline_ns_;
  who_ = std::move(other.who_);
  within_ = std::move(other.within_);
  return *this;
}

TcpConnection::~TcpConnection() {
  if (fd_ >= 0) ::close(fd_);
}

TcpIo TcpConnection::send_all(std::span<const std::uint8_t> bytes) noexcept {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      if (!wait_for(fd_, POLLOUT, deadline_ns_)) return TcpIo::timed_out;
    } else {
      return TcpIo::closed;
    }
  }
  return TcpIo::done;
}

TcpRead TcpConnection::read_some(std::span<std::uint8_t> buffer) noexcept {
  for (;;) {
    const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), 0);
    if (n > 0) return {TcpIo::done, static_cast<std::size_t>(n), 0};
    if (n == 0) return {TcpIo::closed, 0, 0};
    if (errno != EAGAIN && errno != EINTR) return {TcpIo::failed, 0, errno};
    if (!wait_for(fd_, POLLIN, deadline_ns_)) return {TcpIo::timed_out, 0, 0};
  }
}

const std::string& TcpConnection::who() const noexcept { return who_; }
const std::string& TcpConnection::within() const noexcept { return within_; }

std::filesystem::path default_cache_path(const std::string& file_name) {
  std::filesystem::path base;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    base = xdg;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    base = std::filesystem::path(home) / ".cache";
  } else {
    base = std::filesystem::temp_directory_path();
  }
  return base / "sim" / file_name;
}

bool write_atomically(const std::filesystem::path& path, std::string_view text) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  const fs::path temporary = path.string() + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out) ec = std::make_error_code(std::errc::io_error);
  }
  if (!ec) fs::rename(temporary, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
  }
  return !ec;
}

}  // namespace sim::lidar
