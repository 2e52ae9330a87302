// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/ptc_client.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <system_error>
#include <vector>

#include "sim/clock.hpp"
#include "sim/hesai/calibration.hpp"

namespace sim::hesai {
namespace {

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

// A connected TCP socket that closes itself.
class Connection {
 public:
  explicit Connection(int fd) noexcept : fd_(fd) {}
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection() {
    if (fd_ >= 0) ::close(fd_);
  }
  int fd() const noexcept { return fd_; }

 private:
  int fd_;
};

// Waits for `events` on `fd` until `deadline_ns` (monotonic): true when ready.
bool wait_for(int fd, short events, std::int64_t deadline_ns) {
  for (;;) {
    const std::int64_t left_ms = (deadline_ns - sim::monotonic_ns()) / 1'000'000;
    if (left_ms <= 0) return false;
    pollfd p{fd, events, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min<std::int64_t>(left_ms, 1000)));
    if (r > 0) return true;
    if (r < 0 && errno != EINTR) return false;
  }
}

// One PTC exchange: connects, sends `command`, reads the header and exactly the payload it
// announces; `what` names the payload in messages ("calibration", "inventory").
Expected<std::vector<std::uint8_t>> exchange(const PtcEndpoint& sensor, std::uint8_t command,
                                             const std::string& what) {
  const std::string who = "sensor " + sensor.host + ":" + std::to_string(sensor.port);
  const double seconds = static_cast<double>(sensor.timeout.count()) / 1000.0;
  char seconds_text[32];
  std::snprintf(seconds_text, sizeof seconds_text, "%g s", seconds);
  const std::int64_t deadline = sim::monotonic_ns() + sensor.timeout.count() * 1'000'000;

  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(sensor.port);
  if (::inet_pton(AF_INET, sensor.host.c_str(), &address.sin_addr) != 1) {
    return Error{ErrorCode::invalid_argument,
                 "--sensor-ip '" + sensor.host + "' is not an IPv4 address (e.g. 192.168.1.201)"};
  }
  Connection connection(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (connection.fd() < 0) return failed("cannot open a TCP socket: " + std::string(std::strerror(errno)));
  const int fd = connection.fd();

  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    if (errno != EINPROGRESS) {
      return failed(who + " refused the PTC connection (" + std::strerror(errno) +
                    "); check --sensor-ip and that the sensor is on");
    }
    if (!wait_for(fd, POLLOUT, deadline)) {
      return failed(who + " did not accept a PTC connection within " + seconds_text +
                    "; check --sensor-ip and the network");
    }
    int error = 0;
    socklen_t length = sizeof error;
    ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
    if (error != 0) {
      return failed(who + " refused the PTC connection (" + std::strerror(error) +
                    "); check --sensor-ip and that the sensor is on");
    }
  }

  const auto request = ptc::request(command);
  std::size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      if (!wait_for(fd, POLLOUT, deadline)) {
        return failed(who + " did not take the PTC request within " + seconds_text);
      }
    } else {
      return failed(who + " closed the PTC connection before the request was sent");
    }
  }

  // The header first (it says how much follows), then exactly that many bytes.
  std::vector<std::uint8_t> answer;
  std::size_t wanted = ptc::header_size;
  bool header_read = false;
  while (answer.size() < wanted) {
    std::uint8_t chunk[4096];
    const ssize_t n = ::recv(fd, chunk, std::min(sizeof chunk, wanted - answer.size()), 0);
    if (n > 0) {
      answer.insert(answer.end(), chunk, chunk + n);
    } else if (n == 0) {
      if (!header_read && answer.empty()) {
        return failed(who + " closed the PTC connection without answering");
      }
      if (!header_read) break;  // parse_header names the short header
      return failed(who + " closed the PTC connection after " +
                    std::to_string(answer.size() - ptc::header_size) + " of the " +
                    std::to_string(wanted - ptc::header_size) +
                    " " + what + " bytes it announced; try again");
    } else if (errno == EAGAIN || errno == EINTR) {
      if (!wait_for(fd, POLLIN, deadline)) {
        if (answer.empty()) {
          return failed(who + " accepted the PTC connection but did not answer within " +
                        seconds_text);
        }
        return failed(who + " stopped sending after " + std::to_string(answer.size()) +
                      " bytes of its answer (nothing more within " + seconds_text + ")");
      }
      continue;
    } else {
      return failed(who + " broke the PTC connection: " + std::strerror(errno));
    }
    if (!header_read && answer.size() == ptc::header_size) {
      auto header = ptc::parse_header(answer, command);
      if (!header) return failed(who + ": " + header.error().message);
      header_read = true;
      wanted = ptc::header_size + header->payload_size;
    }
  }
  if (!header_read) {
    auto header = ptc::parse_header(answer, command);
    return failed(who + ": " + (header ? "answered no " + what : header.error().message));
  }
  auto payload = ptc::parse_response(answer, command);
  if (!payload) return failed(who + ": " + payload.error().message);
  return std::vector<std::uint8_t>(payload->begin(), payload->end());
}

}  // namespace

Expected<std::string> fetch_calibration_text(const PtcEndpoint& sensor) {
  auto payload = exchange(sensor, ptc::get_calibration, "calibration");
  if (!payload) return payload.error();
  return std::string(reinterpret_cast<const char*>(payload->data()), payload->size());
}

Expected<SensorIdentity> fetch_identity(const PtcEndpoint& sensor) {
  auto payload = exchange(sensor, ptc::get_inventory, "inventory");
  if (!payload) return payload.error();
  auto inventory = ptc::parse_inventory(*payload);
  if (!inventory) {
    return failed("sensor " + sensor.host + ":" + std::to_string(sensor.port) + ": " +
                  inventory.error().message);
  }
  auto fit = [](const std::string& text) { return text.substr(0, SensorInfo::kMaxName); };
  SensorIdentity identity;
  identity.vendor = "Hesai";
  identity.serial = fit(inventory->serial);
  // The sensor firmware is what Hesai's release notes and the web page call the firmware; the
  // control board's version follows it.
  std::string firmware = inventory->sensor_firmware;
  if (!inventory->control_firmware.empty()) {
    firmware += (firmware.empty() ? "control " : ", control ") + inventory->control_firmware;
  }
  identity.firmware = fit(firmware);
  return identity;
}

Expected<FetchedCalibration> calibration_from_sensor(const PtcEndpoint& sensor,
                                                     const std::filesystem::path& cache,
                                                     std::optional<Model> model) {
  namespace fs = std::filesystem;
  std::string why;
  auto text = fetch_calibration_text(sensor);
  if (text) {
    auto calibration =
        Calibration::parse(*text, model, "calibration served by " + sensor.host);
    if (calibration) {
      std::error_code ec;
      if (cache.has_parent_path()) fs::create_directories(cache.parent_path(), ec);
      const fs::path temporary = cache.string() + ".part";
      {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        out.write(text->data(), static_cast<std::streamsize>(text->size()));
        if (!out) ec = std::make_error_code(std::errc::io_error);
      }
      if (!ec) fs::rename(temporary, cache, ec);
      if (ec) {
        fs::remove(temporary, ec);
        return Error{ErrorCode::system_error,
                     "cannot write the sensor's calibration to " + cache.string() +
                         "; pass a writable --calibration path to cache it in"};
      }
      FetchedCalibration fetched;
      fetched.channels = calibration->channels();
      return fetched;
    }
    why = calibration.error().message;
  } else {
    why = text.error().message;
  }
  std::error_code ec;
  if (!fs::is_regular_file(cache, ec)) {
    return Error{ErrorCode::not_found,
                 why + "; and no cached calibration at " + cache.string() + " to fall back on"};
  }
  auto cached = Calibration::load(cache, model);
  if (!cached) {
    return Error{ErrorCode::invalid_argument,
                 why + "; and the cached " + cache.string() + " is unusable too: " +
                     cached.error().message};
  }
  FetchedCalibration fetched;
  fetched.from_cache = true;
  fetched.channels = cached->channels();
  fetched.warning = why + "; using the cached " + cache.string();
  return fetched;
}

std::filesystem::path default_calibration_cache(const std::string& host) {
  std::filesystem::path base;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    base = xdg;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    base = std::filesystem::path(home) / ".cache";
  } else {
    base = std::filesystem::temp_directory_path();
  }
  return base / "sim" / ("hesai-" + host + ".csv");
}

}  // namespace sim::hesai
