// SPDX-License-Identifier: Apache-2.0
#include "sim/lidar/tcp_client.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>
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

// The first IPv4 address getaddrinfo gives for `host` (a name or a literal), with the port, or
// its first address when it has no IPv4 one (sensors are reached over IPv4 as a rule, and a name
// may list an IPv6 address first that no route leads to).
struct Resolved {
  int status = EAI_AGAIN;  // getaddrinfo's result: 0 when `address` holds one
  int error = 0;           // errno, with EAI_SYSTEM
  sockaddr_storage address{};
  socklen_t length = 0;
};

Resolved first_address(const std::string& host, std::uint16_t port, int flags) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = flags;
  addrinfo* list = nullptr;
  Resolved out;
  out.status = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &list);
  if (out.status == EAI_SYSTEM) out.error = errno;
  const addrinfo* chosen = list;
  for (const addrinfo* a = list; a != nullptr; a = a->ai_next) {
    if (a->ai_family == AF_INET) {
      chosen = a;
      break;
    }
  }
  if (out.status == 0 && chosen != nullptr && chosen->ai_addrlen <= sizeof out.address) {
    std::memcpy(&out.address, chosen->ai_addr, chosen->ai_addrlen);
    out.length = chosen->ai_addrlen;
  } else if (out.status == 0) {
    out.status = EAI_FAIL;
  }
  if (list != nullptr) ::freeaddrinfo(list);
  return out;
}

// Resolves `host` before the deadline. getaddrinfo has no timeout of its own (a name such as
// os-122.local may wait on mDNS or a DNS server for many seconds), so a name is resolved on a
// thread of its own that this waits for until the deadline; one that answers late finishes on
// its own and frees what it shares. An address literal needs no thread.
Expected<Resolved> resolve(const std::string& host, std::uint16_t port, std::int64_t deadline_ns,
                           std::chrono::milliseconds timeout) {
  Resolved literal = first_address(host, port, AI_NUMERICHOST);
  if (literal.status == 0) return literal;
  struct Shared {
    std::mutex mutex;
    std::condition_variable done;
    std::optional<Resolved> result;
  };
  auto shared = std::make_shared<Shared>();
  try {
    std::thread([shared, host, port] {
      Resolved r = first_address(host, port, 0);
      const std::lock_guard<std::mutex> lock(shared->mutex);
      shared->result = r;
      shared->done.notify_all();
    }).detach();
  } catch (const std::system_error& e) {
    return failed("cannot start resolving --sensor-ip '" + host + "': " + e.what());
  }
  std::unique_lock<std::mutex> lock(shared->mutex);
  const auto left = std::chrono::nanoseconds(std::max<std::int64_t>(0, deadline_ns - monotonic_ns()));
  if (!shared->done.wait_for(lock, left, [&] { return shared->result.has_value(); })) {
    return failed("the name '" + host + "' (--sensor-ip) did not resolve within " + seconds_text(timeout) +
                  "; check the name, or give the sensor's address (e.g. 192.168.1.201)");
  }
  const Resolved r = *shared->result;
  if (r.status == 0) return r;
  const std::string why = r.status == EAI_SYSTEM ? std::strerror(r.error) : ::gai_strerror(r.status);
  const bool unknown = r.status == EAI_NONAME || r.status == EAI_FAIL;
  return Error{unknown ? ErrorCode::invalid_argument : ErrorCode::system_error,
               "the name '" + host + "' (--sensor-ip) is not an address and does not resolve (" + why +
                   "); give the sensor's address (e.g. 192.168.1.201) or a name that resolves"};
}

}  // namespace

std::string host_problem(const std::string& host) {
  if (host.empty()) return "'' is neither an address nor a name";
  if (first_address(host, 0, AI_NUMERICHOST).status == 0) return {};
  const bool name = host.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.-") ==
                    std::string::npos;
  if (name && host.front() != '-' && host.front() != '.') return {};
  return "'" + host + "' is neither an address (e.g. 192.168.1.201) nor a host name (os-122.local)";
}

Expected<TcpConnection> TcpConnection::connect(const TcpPeer& peer) {
  const std::int64_t deadline = monotonic_ns() + peer.timeout.count() * 1'000'000;
  std::string who = "sensor " + peer.host + ":" + std::to_string(peer.port);
  std::string within = "within " + seconds_text(peer.timeout);
  auto resolved = resolve(peer.host, peer.port, deadline, peer.timeout);
  if (!resolved) return resolved.error();
  const Resolved& address = resolved.value();
  const int fd = ::socket(address.address.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return failed("cannot open a TCP socket: " + std::string(std::strerror(errno)));
  TcpConnection connection(fd, deadline, std::move(who), std::move(within));
  const std::string refused = connection.who_ + " refused the " + peer.service + " connection (";
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address.address), address.length) == 0) return connection;
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
