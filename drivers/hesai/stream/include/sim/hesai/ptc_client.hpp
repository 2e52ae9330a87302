// SPDX-License-Identifier: Apache-2.0
// The sensor's own angle-correction file over PTC (TCP 9347), checked and cached:
//
//   auto got = sim::hesai::calibration_from_sensor({"192.168.1.201"}, "unit.csv", model);
//   if (!got) -> got.error().message: why, and that no cache exists to fall back on
//   got->from_cache -> got->warning says why the sensor's file could not be used
//
// Every step has a deadline (connect, each read, the whole exchange), so a sensor that does
// not answer, or stops answering halfway, costs at most `timeout` and never hangs the driver.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>
#include <string>

#include "sim/hesai/model.hpp"
#include "sim/hesai/ptc.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::hesai {

struct PtcEndpoint {
  std::string host = "192.168.1.201";  // Hesai's factory address
  std::uint16_t port = ptc::default_port;
  std::chrono::milliseconds timeout{3000};  // for the whole exchange
};

// One PTC exchange within sensor.timeout: connects, sends `command` with `payload`, reads the
// whole answer and returns its payload. Errors, one sentence naming the sensor: system_error
// when the connection failed (refused, no answer, closed early, stalled), invalid_argument when
// the sensor answered but not with what was asked (a PTC return code: its firmware lacks the
// command; not PTC). `what` names the answer in messages ("calibration", "PTP status").
Expected<std::vector<std::uint8_t>> ptc_exchange(const PtcEndpoint& sensor, std::uint8_t command,
                                                 std::span<const std::uint8_t> payload,
                                                 const std::string& what);

// Asks the sensor for its angle-correction file and returns its text, or one sentence naming
// the sensor and what went wrong (refused, no answer, closed early, not PTC, stalled).
Expected<std::string> fetch_calibration_text(const PtcEndpoint& sensor);

// Asks the sensor for its inventory (PTC 0x07): vendor "Hesai", the serial number and the
// firmware versions (the model is left to the caller, who knows it from the packets). One
// sentence when the sensor does not answer or the answer is not an inventory.
Expected<SensorIdentity> fetch_identity(const PtcEndpoint& sensor);

struct FetchedCalibration {
  bool from_cache = false;  // the sensor's answer was not usable; the cached file is used
  std::string warning;      // why, when from_cache
  std::size_t channels = 0;
};

// Fetches the sensor's file, checks it like a calibration file (channel count of `model` when
// known, angle ranges) and writes it to `cache` (atomically: a reader never sees half a file).
// When the sensor does not deliver a usable file and `cache` exists, the cache is used with a
// warning; without a cache the result is the error.
Expected<FetchedCalibration> calibration_from_sensor(const PtcEndpoint& sensor,
                                                     const std::filesystem::path& cache,
                                                     std::optional<Model> model);

// Where the calibration of the sensor at `host` is cached when no file is named:
// $XDG_CACHE_HOME/sim/hesai-<host>.csv, else ~/.cache/sim/hesai-<host>.csv.
std::filesystem::path default_calibration_cache(const std::string& host);

}  // namespace sim::hesai
