// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/metadata_client.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <utility>

#include "sim/lidar/tcp_client.hpp"

namespace sim::ouster {
namespace {

constexpr std::size_t max_answer_bytes = 4u << 20;
constexpr char metadata_path[] = "/api/v1/sensor/metadata";

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

// The status and body of a whole HTTP/1.x answer, or why it is not HTTP.
Expected<HttpAnswer> split_answer(const std::string& answer, const std::string& who) {
  const auto end_of_headers = answer.find("\r\n\r\n");
  if (answer.rfind("HTTP/1.", 0) != 0 || end_of_headers == std::string::npos) {
    return failed(who + " did not answer with HTTP; check --sensor-ip and --http-port");
  }
  HttpAnswer split;
  split.status_line = answer.substr(0, std::min<std::size_t>(answer.find("\r\n"), 80));
  for (char& c : split.status_line) c = (c >= 32 && c < 127) ? c : '?';
  const std::string& line = split.status_line;
  split.status = 0;
  if (line.size() >= 12) {
    for (std::size_t i = 9; i < 12 && std::isdigit(static_cast<unsigned char>(line[i])) != 0; ++i) {
      split.status = split.status * 10 + (line[i] - '0');
    }
  }
  split.body = answer.substr(end_of_headers + 4);
  return split;
}

}  // namespace

Expected<HttpAnswer> http_get(const HttpEndpoint& sensor, const std::string& path, std::size_t max_body,
                              const std::string& what) {
  auto connection = lidar::TcpConnection::connect({sensor.host, sensor.port, sensor.timeout, "HTTP"});
  if (!connection) return connection.error();
  const std::string& who = connection->who();
  const std::string request = "GET " + path + " HTTP/1.0\r\nHost: " + sensor.host +
                              "\r\nAccept: application/json\r\n\r\n";
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
      return failed(who + " stopped sending its " + what + " halfway (nothing more " + connection->within() + ")");
    }
    if (got.status == lidar::TcpIo::failed) return failed(who + " broke the connection: " + std::strerror(got.error));
    answer.append(reinterpret_cast<const char*>(chunk), got.size);
    if (answer.size() > max_body) {
      const std::string limit = max_body >= (1u << 20) ? std::to_string(max_body >> 20) + " MB"
                                                       : std::to_string(max_body >> 10) + " KB";
      return failed(who + " sent more than " + limit + " for its " + what + "; it is not an Ouster sensor");
    }
  }
  return split_answer(answer, who);
}

Expected<std::string> fetch_metadata_text(const HttpEndpoint& sensor) {
  auto answer = http_get(sensor, metadata_path, max_answer_bytes, "metadata");
  if (!answer) return answer.error();
  if (answer->status != 200) {
    return failed("sensor " + sensor.host + ":" + std::to_string(sensor.port) + " answered '" +
                  answer->status_line + "' to GET " + metadata_path + "; its firmware may be older than 2.0");
  }
  return std::move(answer->body);
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
