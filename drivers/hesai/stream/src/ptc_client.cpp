// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/ptc_client.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include "sim/hesai/calibration.hpp"
#include "sim/hesai/ptc_time.hpp"
#include "sim/lidar/tcp_client.hpp"

namespace sim::hesai {
namespace {

Error failed(const std::string& message) { return Error{ErrorCode::system_error, message}; }

// Reads the header (it says how much follows), then exactly the payload it announces; `what`
// names the payload in messages ("calibration", "inventory").
Expected<std::vector<std::uint8_t>> read_answer(lidar::TcpConnection& connection, std::uint8_t command,
                                                const std::string& what) {
  const std::string& who = connection.who();
  std::vector<std::uint8_t> answer;
  std::size_t wanted = ptc::header_size;
  bool header_read = false;
  while (answer.size() < wanted) {
    std::uint8_t chunk[4096];
    const lidar::TcpRead got = connection.read_some({chunk, std::min(sizeof chunk, wanted - answer.size())});
    if (got.status == lidar::TcpIo::closed) {
      if (!header_read && answer.empty()) return failed(who + " closed the PTC connection without answering");
      if (!header_read) break;  // parse_header names the short header
      return failed(who + " closed the PTC connection after " + std::to_string(answer.size() - ptc::header_size) +
                    " of the " + std::to_string(wanted - ptc::header_size) + " " + what +
                    " bytes it announced; try again");
    }
    if (got.status == lidar::TcpIo::timed_out) {
      if (answer.empty()) return failed(who + " accepted the PTC connection but did not answer " + connection.within());
      return failed(who + " stopped sending after " + std::to_string(answer.size()) +
                    " bytes of its answer (nothing more " + connection.within() + ")");
    }
    if (got.status == lidar::TcpIo::failed) {
      return failed(who + " broke the PTC connection: " + std::strerror(got.error));
    }
    answer.insert(answer.end(), chunk, chunk + got.size);
    if (!header_read && answer.size() == ptc::header_size) {
      auto header = ptc::parse_header(answer, command);
      if (!header) return Error{header.error().code, who + ": " + header.error().message};
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

Expected<std::vector<std::uint8_t>> ptc_exchange(const PtcEndpoint& sensor, std::uint8_t command,
                                                 std::span<const std::uint8_t> payload,
                                                 const std::string& what) {
  auto connection = lidar::TcpConnection::connect({sensor.host, sensor.port, sensor.timeout, "PTC"});
  if (!connection) return connection.error();
  const auto request = ptc::request(command, payload);
  const lidar::TcpIo sent = connection->send_all(request);
  if (sent == lidar::TcpIo::timed_out) {
    return failed(connection->who() + " did not take the PTC request " + connection->within());
  }
  if (sent != lidar::TcpIo::done) {
    return failed(connection->who() + " closed the PTC connection before the request was sent");
  }
  return read_answer(*connection, command, what);
}

namespace {

Expected<std::vector<std::uint8_t>> exchange(const PtcEndpoint& sensor, std::uint8_t command,
                                             const std::string& what) {
  return ptc_exchange(sensor, command, {}, what);
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
  auto fit = [](const std::string& text) { return sensor_text(text, SensorInfo::kMaxName); };
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
      if (!lidar::write_atomically(cache, *text)) {
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
  return lidar::default_cache_path("hesai-" + host + ".csv");
}

}  // namespace sim::hesai
