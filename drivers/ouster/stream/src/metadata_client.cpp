// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/metadata_client.hpp"

#include <cstring>
#include <utility>

#include "sim/lidar/tcp_client.hpp"

namespace sim::ouster {
namespace {

constexpr std::size_t max_answer_bytes = 4u << 20;
constexpr char metadata_path[] = "/api/v1/sensor/metadata";

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

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

}  // namespace

Expected<std::string> fetch_metadata_text(const HttpEndpoint& sensor) {
  auto connection = lidar::TcpConnection::connect({sensor.host, sensor.port, sensor.timeout, "HTTP"});
  if (!connection) return connection.error();
  const std::string& who = connection->who();
  const std::string request = std::string("GET ") + metadata_path + " HTTP/1.0\r\nHost: " +
                              sensor.host + "\r\nAccept: application/json\r\n\r\n";
  const lidar::TcpIo sent = connection->send_all(
      {reinterpret_cast<const std::uint8_t*>(request.data()), request.size()});
  if (sent == lidar::TcpIo::timed_out) return failed(who + " did not take the request " + connection->within());
  if (sent != lidar::TcpIo::done) return failed(who + " closed the connection before the request was sent");
  // HTTP/1.0: the answer ends when the sensor closes the connection.
  std::string answer;
  for (;;) {
    std::uint8_t chunk[8192];
    const lidar::TcpRead got = connection->read_some(chunk);
    if (got.status == lidar::TcpIo::closed) break;
    if (got.status == lidar::TcpIo::timed_out && answer.empty()) {
      return failed(who + " accepted the connection but did not answer " + connection->within());
    }
    if (got.status == lidar::TcpIo::timed_out) {
      return failed(who + " stopped sending its metadata halfway (nothing more " + connection->within() + ")");
    }
    if (got.status == lidar::TcpIo::failed) return failed(who + " broke the connection: " + std::strerror(got.error));
    answer.append(reinterpret_cast<const char*>(chunk), got.size);
    if (answer.size() > max_answer_bytes) {
      return failed(who + " sent more than 4 MB for its metadata; it is not an Ouster sensor");
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
      if (!lidar::write_atomically(cache, *text)) {
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
  return lidar::default_cache_path("ouster-" + host + ".json");
}

}  // namespace sim::ouster
