// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/ptc_time.hpp"

#include "sim/hesai/ptc.hpp"

#include <cstdio>

namespace sim::hesai::ptc {
namespace {

Error too_short(std::span<const std::uint8_t> payload, std::size_t needed, const char* what) {
  return Error{ErrorCode::invalid_argument,
               std::string("the ") + what + " answer is " + std::to_string(payload.size()) +
                   " bytes, shorter than the " + std::to_string(needed) + " of its layout"};
}

std::uint64_t be(std::span<const std::uint8_t> bytes, std::size_t at, std::size_t size) noexcept {
  std::uint64_t value = 0;
  for (std::size_t i = 0; i < size; ++i) value = (value << 8) | bytes[at + i];
  return value;
}
std::int64_t be_i64(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::int64_t>(be(b, at, 8));
}
std::int32_t be_i32(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(be(b, at, 4)));
}
std::uint16_t be_u16(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::uint16_t>(be(b, at, 2));
}

ClockIdentity identity_at(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  ClockIdentity id{};
  for (std::size_t i = 0; i < id.size(); ++i) id[i] = b[at + i];
  return id;
}

// Where the clock comes from and the PTP domain, from the PTP config (when the sensor gave it)
// and the status (PTP lock or GPS lock seen).
void set_source(const ClockReplies& r, ClockStatus& clock) {
  const bool gps_fields = r.status && r.status->gps_pps_locked.has_value();
  const bool gps_seen = gps_fields && (*r.status->gps_pps_locked || *r.status->gps_gprmc_locked);
  if (r.config) {
    if (r.config->enabled) {
      clock.source = r.config->profile == 0 ? ClockSource::ptp : ClockSource::gptp;
      clock.ptp_domain = r.config->domain;
    } else {
      // PTP is off: the sensor takes GPS (PPS + $GPRMC) when it has the inputs, else runs free.
      clock.source = gps_fields ? ClockSource::pps_nmea : ClockSource::free_running;
    }
    return;
  }
  // An older firmware without 0x26: a PTP port or a PTP lock says PTP, a GPS lock says GPS.
  const bool ptp_seen = (r.status && r.status->ptp_status != 0) ||
                        (r.port && r.port->port_state == static_cast<std::uint8_t>(PortState::slave));
  if (ptp_seen) {
    clock.source = ClockSource::ptp;
  } else if (gps_seen) {
    clock.source = ClockSource::pps_nmea;
  }
}

ClockState state_from_port(std::uint8_t port_state) noexcept {
  switch (static_cast<PortState>(port_state)) {
    case PortState::slave: return ClockState::locked;
    case PortState::initializing:
    case PortState::listening:
    case PortState::uncalibrated: return ClockState::acquiring;
    case PortState::faulty:
    case PortState::disabled:
    case PortState::pre_master:
    case PortState::master:
    case PortState::passive:
    case PortState::grand_master: return ClockState::free_running;  // no master of its own
  }
  return ClockState::unknown;
}

void set_ptp(const ClockReplies& r, ClockStatus& clock) {
  if (r.status) {
    switch (static_cast<PtpLock>(r.status->ptp_status)) {
      case PtpLock::free_run: clock.state = ClockState::free_running; break;
      case PtpLock::tracking: clock.state = ClockState::acquiring; break;
      case PtpLock::locked: clock.state = ClockState::locked; break;
      case PtpLock::frozen: clock.state = ClockState::holdover; break;
      default: clock.state = ClockState::unknown; break;
    }
  } else if (r.port) {
    clock.state = state_from_port(r.port->port_state);
  }
  if (r.ptp) {
    clock.offset_from_master_ns = r.ptp->master_offset_ns;
  } else if (r.time_status) {
    clock.offset_from_master_ns = r.time_status->master_offset_ns;
  }
  if (r.port && r.port->delay_mechanism == 2) clock.path_delay_ns = r.port->peer_mean_path_delay_ns;
  if (r.time_status && r.time_status->gm_present) {
    // Its own clock as grandmaster is no synchronisation, whatever the lock byte says.
    if (r.port && r.port->clock == r.time_status->gm_identity) {
      if (clock.state == ClockState::locked) clock.state = ClockState::free_running;
    } else {
      clock.grandmaster = clock_identity_text(r.time_status->gm_identity);
    }
  }
  if (r.grandmaster && r.grandmaster->utc_offset_valid()) {
    clock.utc_offset_s = r.grandmaster->utc_offset_s;
  }
  if (r.grandmaster) clock.ptp_timescale = r.grandmaster->ptp_timescale();
}

void set_gps(const LidarStatus& status, ClockStatus& clock) {
  if (!status.gps_pps_locked) return;
  const bool pps = *status.gps_pps_locked;
  const bool nmea = status.gps_gprmc_locked.value_or(false);
  clock.state = pps && nmea ? ClockState::locked
                : pps || nmea ? ClockState::acquiring
                              : ClockState::free_running;
}

}  // namespace

std::vector<std::uint8_t> request(std::uint8_t command, std::span<const std::uint8_t> payload) {
  const auto n = static_cast<std::uint32_t>(payload.size());
  std::vector<std::uint8_t> bytes(header_size + payload.size());
  bytes[0] = 0x47;
  bytes[1] = 0x74;
  bytes[2] = command;
  for (std::size_t i = 0; i < 4; ++i) bytes[4 + i] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
  for (std::size_t i = 0; i < payload.size(); ++i) bytes[header_size + i] = payload[i];
  return bytes;
}

std::string clock_identity_text(const ClockIdentity& id) {
  char text[24];
  std::snprintf(text, sizeof text, "%02x%02x%02x.%02x%02x.%02x%02x%02x", id[0], id[1], id[2], id[3], id[4],
                id[5], id[6], id[7]);
  return text;
}

Expected<PtpStatus> parse_ptp_status(std::span<const std::uint8_t> p) {
  if (p.size() < ptp_status_size) return too_short(p, ptp_status_size, "PTP status");
  return PtpStatus{be_i64(p, 0), be_i32(p, 8), be_i32(p, 12)};
}

Expected<PortDataSet> parse_port_data_set(std::span<const std::uint8_t> p) {
  if (p.size() < port_data_set_size) return too_short(p, port_data_set_size, "PTP port data set");
  PortDataSet port;
  port.clock = identity_at(p, 0);
  port.port_number = be_u16(p, 8);
  port.port_state = p[10];
  // TimeInterval: ns × 2^16; an arithmetic shift keeps the sign and cannot overflow.
  port.peer_mean_path_delay_ns = be_i64(p, 12) >> 16;
  port.delay_mechanism = p[23];
  port.version = p[25];
  return port;
}

Expected<TimeStatusNp> parse_time_status_np(std::span<const std::uint8_t> p) {
  if (p.size() < time_status_np_size) return too_short(p, time_status_np_size, "PTP time status");
  TimeStatusNp status;
  status.master_offset_ns = be_i64(p, 0);
  status.ingress_time_ns = be_i64(p, 8);
  // @16 cumulativeScaledRateOffset i32, @20 scaledLastGmPhaseChange i32, @24 gmTimeBaseIndicator
  // u16, @26 lastGmPhaseChange (12), @38 gmPresent i32, @42 gmIdentity.
  status.gm_present = be_i32(p, 38) != 0;
  status.gm_identity = identity_at(p, 42);
  return status;
}

Expected<GrandmasterSettingsNp> parse_grandmaster_settings_np(std::span<const std::uint8_t> p) {
  if (p.size() < grandmaster_settings_np_size) {
    return too_short(p, grandmaster_settings_np_size, "PTP grandmaster settings");
  }
  GrandmasterSettingsNp settings;
  settings.clock_class = p[0];
  settings.clock_accuracy = p[1];
  settings.offset_scaled_log_variance = be_u16(p, 2);
  settings.utc_offset_s = static_cast<std::int16_t>(be_u16(p, 4));
  settings.time_flags = p[6];
  settings.time_source = p[7];
  return settings;
}

std::optional<StatusLayout> status_layout(Model model) noexcept {
  switch (model) {
    case Model::pandar64:
    case Model::pandar40p:
    case Model::pandar_xt32:
    case Model::pandar_xt16:
    case Model::pandar_xt32m: return StatusLayout::xt;
    case Model::pandar_qt128: return StatusLayout::qt;
    case Model::pandar_qt64: return std::nullopt;
  }
  return std::nullopt;
}

Expected<LidarStatus> parse_lidar_status(std::span<const std::uint8_t> p, std::optional<StatusLayout> layout) {
  const StatusLayout chosen = layout.value_or(p.size() == 58 ? StatusLayout::qt : StatusLayout::xt);
  LidarStatus status;
  if (chosen == StatusLayout::qt) {
    if (p.size() < 53) return too_short(p, 53, "LiDAR status");
    status.ptp_status = p[52];
    return status;
  }
  if (p.size() < 49) return too_short(p, 49, "LiDAR status");
  status.gps_pps_locked = p[38] == 1;
  status.gps_gprmc_locked = p[39] == 1;
  status.ptp_status = p[48];
  return status;
}

Expected<PtpConfig> parse_ptp_config(std::span<const std::uint8_t> p) {
  if (p.size() < 4) return too_short(p, 4, "PTP configuration");
  return PtpConfig{p[0] != 0, p[1], p[2], p[3]};
}

ClockStatus clock_status(const ClockReplies& replies) {
  ClockStatus clock;
  clock.stamps = StampClock::sensor;
  set_source(replies, clock);
  switch (clock.source) {
    case ClockSource::ptp:
    case ClockSource::gptp: set_ptp(replies, clock); break;
    case ClockSource::pps_nmea:
      if (replies.status) set_gps(*replies.status, clock);
      break;
    case ClockSource::free_running: clock.state = ClockState::free_running; break;
    default: break;
  }
  return clock;
}

}  // namespace sim::hesai::ptc
