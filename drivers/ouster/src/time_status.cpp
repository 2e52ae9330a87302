// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/time_status.hpp"

#include <cctype>
#include <cmath>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace sim::ouster {
namespace {

using Json = nlohmann::json;

const Json* member(const Json* object, const char* key) {
  if (object == nullptr || !object->is_object()) return nullptr;
  const auto found = object->find(key);
  return found == object->end() ? nullptr : &*found;
}

// A number as whole nanoseconds (pmc prints some as floats: "-2.0"); nullopt for any other type,
// or a number no int64 holds.
std::optional<std::int64_t> integer(const Json* value) {
  if (value == nullptr) return std::nullopt;
  if (value->is_number_integer() && !value->is_number_unsigned()) return value->get<std::int64_t>();
  if (value->is_number_unsigned()) {
    const auto u = value->get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(INT64_MAX)) return std::nullopt;
    return static_cast<std::int64_t>(u);
  }
  if (value->is_number_float()) {
    const double d = value->get<double>();
    // 2^63 is exactly representable; anything at or beyond it (or NaN) is not an int64.
    if (!std::isfinite(d) || d >= 9223372036854775808.0 || d < -9223372036854775808.0) return std::nullopt;
    return static_cast<std::int64_t>(std::llround(d));
  }
  return std::nullopt;
}

// 0/1 or true/false.
std::optional<bool> flag(const Json* value) {
  if (value == nullptr) return std::nullopt;
  if (value->is_boolean()) return value->get<bool>();
  if (auto n = integer(value)) return *n != 0;
  return std::nullopt;
}

std::string text(const Json* value) {
  return value != nullptr && value->is_string() ? value->get<std::string>() : std::string();
}

// A clock identity as ptp4l prints it ("001747.fffe.700038"), lower case; "" when the text is
// not one (whatever the sensor sent, nothing else reaches the report).
std::string identity(const std::string& raw) {
  const std::string id = raw.substr(0, raw.find('-'));  // a port identity ends in "-<port>"
  if (id.size() != 18 || id[6] != '.' || id[11] != '.') return {};
  std::string out;
  for (std::size_t i = 0; i < id.size(); ++i) {
    const char c = id[i];
    if (i == 6 || i == 11) {
      out += '.';
    } else if (std::isxdigit(static_cast<unsigned char>(c)) != 0) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      return {};
    }
  }
  return out;
}

void set_source(const Json* sensor, ClockStatus& clock) {
  const std::string mode = text(member(member(sensor, "timestamp"), "mode"));
  if (mode == "TIME_FROM_PTP_1588") {
    clock.source = ClockSource::ptp;
  } else if (mode == "TIME_FROM_SYNC_PULSE_IN") {
    const bool pulse = flag(member(member(sensor, "sync_pulse_in"), "locked")).value_or(false);
    const bool nmea = flag(member(member(sensor, "nmea"), "locked")).value_or(false);
    clock.source = nmea ? ClockSource::pps_nmea : ClockSource::sync_pulse;
    // Pulses counted but no NMEA: seconds since power-on, synchronised in phase only.
    clock.state = pulse ? ClockState::locked : ClockState::acquiring;
  } else if (mode == "TIME_FROM_INTERNAL_OSC") {
    clock.source = ClockSource::free_running;
    clock.state = ClockState::free_running;
  }
}

void set_ptp(const Json* ptp, ClockStatus& clock) {
  const Json* port = member(ptp, "port_data_set");
  const Json* current = member(ptp, "current_data_set");
  const Json* properties = member(ptp, "time_properties_data_set");
  const std::string port_state = text(member(port, "port_state"));
  const std::string own = identity(text(member(port, "port_identity")));
  std::string grandmaster = identity(text(member(member(ptp, "parent_data_set"), "grandmaster_identity")));
  if (grandmaster.empty()) grandmaster = identity(text(member(member(ptp, "time_status_np"), "gm_identity")));
  const bool own_master = !grandmaster.empty() && grandmaster == own;
  if (port_state == "SLAVE") {
    clock.state = own_master ? ClockState::acquiring : ClockState::locked;
  } else if (port_state == "LISTENING" || port_state == "UNCALIBRATED" || port_state == "INITIALIZING") {
    clock.state = ClockState::acquiring;
  } else if (!port_state.empty()) {
    clock.state = ClockState::free_running;  // MASTER, FAULTY, DISABLED, PASSIVE: no master of its own
  }
  if (!own_master) clock.grandmaster = grandmaster;
  clock.offset_from_master_ns = integer(member(current, "offset_from_master"));
  clock.path_delay_ns = integer(member(current, "mean_path_delay"));
  if (const auto domain = integer(member(member(ptp, "default_data_set"), "domain_number"));
      domain && *domain >= 0 && *domain <= 255) {
    clock.ptp_domain = static_cast<std::int32_t>(*domain);
  }
  const auto offset = integer(member(properties, "current_utc_offset"));
  if (offset && *offset >= -1000 && *offset <= 1000 &&
      flag(member(properties, "current_utc_offset_valid")).value_or(false)) {
    clock.utc_offset_s = static_cast<std::int32_t>(*offset);
  }
  clock.ptp_timescale = flag(member(properties, "ptp_timescale")).value_or(false);
}

}  // namespace

Expected<ClockStatus> clock_status_from_time_json(std::string_view json) {
  const Json root = Json::parse(json.begin(), json.end(), nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) {
    return Error{ErrorCode::invalid_argument, "the sensor's time answer is not JSON"};
  }
  // A part that is not an object is no part.
  const Json* sensor = member(&root, "sensor");
  const Json* ptp = member(&root, "ptp");
  if (sensor != nullptr && !sensor->is_object()) sensor = nullptr;
  if (ptp != nullptr && !ptp->is_object()) ptp = nullptr;
  if (!root.is_object() || (sensor == nullptr && ptp == nullptr)) {
    return Error{ErrorCode::invalid_argument,
                 "the sensor's time answer has neither \"sensor\" nor \"ptp\"; it is not an Ouster "
                 "/api/v1/time answer"};
  }
  ClockStatus clock;
  clock.stamps = StampClock::sensor;
  set_source(sensor, clock);
  // Without the timestamp mode (an answer holding only "ptp"), PTP data is taken as the source.
  if (clock.source == ClockSource::ptp || (sensor == nullptr && ptp != nullptr)) {
    clock.source = ClockSource::ptp;
    set_ptp(ptp, clock);
  }
  return clock;
}

}  // namespace sim::ouster
