// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/metadata_client.hpp"

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

#include "sim/clock.hpp"

namespace sim::ouster {
namespace {

constexpr std::size_t max_answer_bytes = 4u << 20;
constexpr char metadata_path[] = "/api/v1/sensor/metadata";

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

class Socket {
 public:
  explicit Socket(int fd) noexcept : fd_(fd) {}
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  ~Socket() {
    if (fd_ >= 0) ::close(fd_);
  }
  int fd() const noexcept { return fd_; }

 private:
  int fd_;
};

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

Expected<void> connect_before(int fd, const sockaddr_in& address, std::int64_t deadline,
                              const std::string& who) {
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) return {};
  if (errno != EINPROGRESS) {
    return failed(who + " refused the HTTP connection (" + std::strerror(errno) +
                  "); check --sensor-ip and that the sensor is on");
  }
  if (!wait_for(fd, POLLOUT, deadline)) {
    return failed(who + " did not accept an HTTP connection in time; check --sensor-ip and the network");
  }
  int error = 0;
  socklen_t length = sizeof error;
  ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
  if (error != 0) {
    return failed(who + " refused the HTTP connection (" + std::strerror(error) +
                  "); check --sensor-ip and that the sensor is on");
  }
  return {};
}

// The body of a whole HTTP/1.x answer, or why it is not a 200 with a body.
Expected<std::string> body_of(const std::string& answer, const std::string& who) {
  const auto end_of_headers = answer.find("\r\n\r\n");
  if (answer.rfind("HTTP/1.", 0) != 0 || end_of_headers == std::string::npos) {
    return failed(who + " did not answer with HTTP; check --sensor-ip and --http-port");
  }
  const std::string status_line = answer.substr(0, answer.find("\r\n"));
  if (status_line.size() < 12 || status_line.compare(9, 3, "200") != 0) {
    std::string shown = status_line.substr(0, 80);
    for (char& c : shown) c = (c >= 32 && c < 127) ? c : '?';
    return failed(who + " answered '" + shown + "' to GET " + metadata_path +
                  "; its firmware may be older than 2.0");
  }
  return answer.substr(end_of_headers + 4);
}

bool write_atomically(const std::filesystem::path& path, const std::string& text) {
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
  if (ec) fs::remove(temporary, ec);
  return !ec;
}

}  // namespace

Expected<std::string> fetch_metadata_text(const HttpEndpoint& sensor) {
  const std::string who = "sensor " + sensor.host + ":" + std::to_string(sensor.port);
  const std::int64_t deadline = monotonic_ns() + sensor.timeout.count() * 1'000'000;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(sensor.port);
  if (::inet_pton(AF_INET, sensor.host.c_str(), &address.sin_addr) != 1) {
    return Error{ErrorCode::invalid_argument,
                 "--sensor-ip '" + sensor.host + "' is not an IPv4 address (e.g. 169.254.0.1)"};
  }
  Socket socket(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (socket.fd() < 0) return failed("cannot open a TCP socket: " + std::string(std::strerror(errno)));
  if (auto connected = connect_before(socket.fd(), address, deadline, who); !connected) {
    return connected.error();
  }
  const std::string request = std::string("GET ") + metadata_path + " HTTP/1.0\r\nHost: " +
                              sensor.host + "\r\nAccept: application/json\r\n\r\n";
  std::size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = ::send(socket.fd(), request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      if (!wait_for(socket.fd(), POLLOUT, deadline)) return failed(who + " did not take the request in time");
    } else {
      return failed(who + " closed the connection before the request was sent");
    }
  }
  // HTTP/1.0: the answer ends when the sensor closes the connection.
  std::string answer;
  for (;;) {
    char chunk[8192];
    const ssize_t n = ::recv(socket.fd(), chunk, sizeof chunk, 0);
    if (n > 0) {
      answer.append(chunk, static_cast<std::size_t>(n));
      if (answer.size() > max_answer_bytes) {
        return failed(who + " sent more than 4 MB for its metadata; it is not an Ouster sensor");
      }
    } else if (n == 0) {
      break;
    } else if (errno == EAGAIN || errno == EINTR) {
      if (!wait_for(socket.fd(), POLLIN, deadline)) {
        return failed(who + (answer.empty() ? " accepted the connection but did not answer in time"
                                            : " stopped sending its metadata halfway"));
      }
    } else {
      return failed(who + " broke the connection: " + std::strerror(errno));
    }
  }
  return body_of(answer, who);
}

Expected<FetchedMetadata> metadata_from_sensor(const HttpEndpoint& sensor,
                                               const std::filesystem::path& cache) {
  std::string why;
  auto text = fetch_metadata_text(sensor);
  if (text) {
    auto parsed = Metadata::parse(*text);
    if (parsed) {
      if (!write_atomically(cache, *text)) {
        return Error{ErrorCode::system_error, "cannot write the sensor's metadata to " + cache.string() +
                                                  "; pass a writable --calibration path to cache it in"};
      }
      return FetchedMetadata{std::move(parsed.value()), false, {}};
    }
    why = "the metadata sensor " + sensor.host + " served is unusable: " + parsed.error().message;
  } else {
    why = text.error().message;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(cache, ec)) {
    return Error{ErrorCode::not_found, why + "; and no cached metadata at " + cache.string() + " to fall back on"};
  }
  auto cached = Metadata::load(cache);
  if (!cached) {
    return Error{ErrorCode::invalid_argument,
                 why + "; and the cached metadata is unusable too: " + cached.error().message};
  }
  return FetchedMetadata{std::move(cached.value()), true, why + "; using the cached " + cache.string()};
}

std::filesystem::path default_metadata_cache(const std::string& host) {
  std::filesystem::path base;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    base = xdg;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    base = std::filesystem::path(home) / ".cache";
  } else {
    base = std::filesystem::temp_directory_path();
  }
  return base / "sim" / ("ouster-" + host + ".json");
}

}  // namespace sim::ouster
