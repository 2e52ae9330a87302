// SPDX-License-Identifier: Apache-2.0
// The sensor's metadata over its HTTP API (GET /api/v1/sensor/metadata), checked and cached:
//
//   auto got = sim::ouster::metadata_from_sensor({"169.254.0.5"}, cache_path);  // IPv4 only: a
//   name such as os-<serial>.local is not resolved (--sensor-ip refuses it in one sentence)
//   if (!got) -> got.error().message: why, and that no cache exists to fall back on
//   got->from_cache -> got->warning says why the sensor's answer could not be used
//
// Every step has a deadline (connect, each read, the whole exchange), so a sensor that does not
// answer, or stops answering halfway, costs at most `timeout` and never hangs the driver.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "sim/ouster/metadata.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

struct HttpEndpoint {
  std::string host = "169.254.0.1";  // an IPv4 address
  std::uint16_t port = 80;
  std::chrono::milliseconds timeout{5000};  // for the whole exchange
};

// A whole HTTP/1.x answer: its status code (0 when the status line has none), the status line
// (printable, at most 80 bytes) and the body.
struct HttpAnswer {
  int status = 0;
  std::string status_line;
  std::string body;
};

// GET `path` (HTTP/1.0, so the sensor closes when done) within sensor.timeout. Errors, one
// sentence naming the sensor: refused, no answer, stopped halfway, more than `max_body` bytes,
// not HTTP. `what` names the answer in messages ("metadata", "time").
Expected<HttpAnswer> http_get(const HttpEndpoint& sensor, const std::string& path, std::size_t max_body,
                              const std::string& what);

// The body of the sensor's answer to GET /api/v1/sensor/metadata (HTTP/1.0, so the sensor
// closes when done), or one sentence naming the sensor and what went wrong. Bodies above 4 MB
// are refused.
Expected<std::string> fetch_metadata_text(const HttpEndpoint& sensor);

struct FetchedMetadata {
  Metadata metadata;
  bool from_cache = false;  // the sensor's answer was not usable; the cached file is used
  std::string warning;      // why, when from_cache
};

// Fetches and parses the sensor's metadata and writes it to `cache` (atomically). When the
// sensor does not deliver usable metadata and `cache` exists, the cache is used with a warning;
// without a cache the result is the error.
Expected<FetchedMetadata> metadata_from_sensor(const HttpEndpoint& sensor,
                                               const std::filesystem::path& cache);

// $XDG_CACHE_HOME/sim/ouster-<host>.json, else ~/.cache/sim/ouster-<host>.json.
std::filesystem::path default_metadata_cache(const std::string& host);

}  // namespace sim::ouster
