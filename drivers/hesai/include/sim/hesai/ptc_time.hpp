// SPDX-License-Identifier: Apache-2.0
// What a Hesai sensor says about its clock over PTC (TCP 9347), the bytes only: the requests and
// the bounds-checked readers of the answers, and how they make a sim::ClockStatus. No I/O here;
// the client that asks once a second is sim/hesai/ptc_clock.hpp.
//
// Commands (PTC 1.0; every multi-byte field big-endian; sources in docs/hesai.md, "Clock"):
//   0x06 PTP diagnostics, 1 payload byte = the query:
//        1 PTP STATUS (16 B)               master_offset i64 ns, ptp_state i32, elapsed ms i32
//        2 PORT_DATA_SET (26 B)            linuxptp's portDS: clockIdentity[8], portNumber u16,
//                                          portState u8, …, peerMeanPathDelay i64 (ns × 2^16), …
//        3 TIME_STATUS_NP (50 B)           linuxptp's: master_offset i64 ns, ingress_time i64,
//                                          …, gmPresent i32 @38, gmIdentity[8] @42
//        4 GRANDMASTER_SETTINGS_NP (8 B)   clockQuality (4), utc_offset i16, time_flags, time_source
//   0x09 LiDAR status: gps_pps_lock @38, gps_gprmc_status @39, ptp_status @48 (XT16/32/40P/64,
//        OT128; 54 B); QT128/AT128: ptp_status @52 (58 B), no GPS fields
//   0x26 PTP config: status (0 disabled), profile (0 1588v2, 1 802.1AS, 2/3 automotive), domain,
//        network (0 UDP/IP, 1 L2), …
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/hesai/model.hpp"
#include "sim/result.hpp"

namespace sim::hesai::ptc {

inline constexpr std::uint8_t ptp_diagnostics = 0x06;
inline constexpr std::uint8_t get_lidar_status = 0x09;
inline constexpr std::uint8_t get_ptp_config = 0x26;

enum class PtpQuery : std::uint8_t {
  status = 1,
  port_data_set = 2,
  time_status_np = 3,
  grandmaster_settings_np = 4,
};

// A request with a payload (the 0x06 query byte): the header announces its length.
std::vector<std::uint8_t> request(std::uint8_t command, std::span<const std::uint8_t> payload);

using ClockIdentity = std::array<std::uint8_t, 8>;
// "xxxxxx.xxxx.xxxxxx", as ptp4l and pmc print it.
std::string clock_identity_text(const ClockIdentity& identity);

inline constexpr std::size_t ptp_status_size = 16;
struct PtpStatus {
  std::int64_t master_offset_ns = 0;
  std::int32_t ptp_state = 0;  // values are the vendor manual's (not relied on: 0x09 says the state)
  std::int32_t elapsed_ms = 0;
};

// linuxptp's portState values (fsm.h).
enum class PortState : std::uint8_t {
  initializing = 1, faulty = 2, disabled = 3, listening = 4, pre_master = 5, master = 6,
  passive = 7, uncalibrated = 8, slave = 9, grand_master = 10,
};

inline constexpr std::size_t port_data_set_size = 26;
struct PortDataSet {
  ClockIdentity clock{};  // the sensor's own clock
  std::uint16_t port_number = 0;
  std::uint8_t port_state = 0;               // PortState
  std::int64_t peer_mean_path_delay_ns = 0;  // TimeInterval / 2^16; meaningful with peer delay
  std::uint8_t delay_mechanism = 0;          // 1 E2E, 2 P2P
  std::uint8_t version = 0;
};

inline constexpr std::size_t time_status_np_size = 50;
struct TimeStatusNp {
  std::int64_t master_offset_ns = 0;
  std::int64_t ingress_time_ns = 0;  // the last PTP message, sensor clock
  bool gm_present = false;           // false when the sensor's clock is its own grandmaster
  ClockIdentity gm_identity{};
};

inline constexpr std::size_t grandmaster_settings_np_size = 8;
struct GrandmasterSettingsNp {
  std::uint8_t clock_class = 0;
  std::uint8_t clock_accuracy = 0;
  std::uint16_t offset_scaled_log_variance = 0;
  std::int16_t utc_offset_s = 0;
  std::uint8_t time_flags = 0;  // PTP flagField[1]: bit 2 UTC offset valid, bit 3 PTP timescale
  std::uint8_t time_source = 0;
  bool utc_offset_valid() const noexcept { return (time_flags & 0x04) != 0; }
  bool ptp_timescale() const noexcept { return (time_flags & 0x08) != 0; }
};

// Where 0x09 puts its clock fields.
enum class StatusLayout {
  xt,  // XT16/32/32M, Pandar40P/64, OT128: GPS fields @38/39, ptp_status @48
  qt,  // QT128, AT128: ptp_status @52, no GPS fields
};
// The layout a model's status answer has; nullopt when not known (QT64): chosen by its size.
std::optional<StatusLayout> status_layout(Model model) noexcept;

// ptp_status of 0x09.
enum class PtpLock : std::uint8_t { free_run = 0, tracking = 1, locked = 2, frozen = 3 };

struct LidarStatus {
  std::uint8_t ptp_status = 0;               // PtpLock (other values: unknown)
  std::optional<bool> gps_pps_locked;        // nullopt: the layout has no GPS fields
  std::optional<bool> gps_gprmc_locked;
};

struct PtpConfig {
  bool enabled = false;
  std::uint8_t profile = 0;  // 0 IEEE 1588v2, 1 802.1AS, 2 and 3 802.1AS automotive
  std::uint8_t domain = 0;
  std::uint8_t network = 0;  // 0 UDP/IP, 1 layer 2
};

// Each reader takes the answer's payload (after the 8-byte header) and refuses, in one
// sentence, one shorter than its layout; longer ones (newer firmware) are read for these fields.
Expected<PtpStatus> parse_ptp_status(std::span<const std::uint8_t> payload);
Expected<PortDataSet> parse_port_data_set(std::span<const std::uint8_t> payload);
Expected<TimeStatusNp> parse_time_status_np(std::span<const std::uint8_t> payload);
Expected<GrandmasterSettingsNp> parse_grandmaster_settings_np(std::span<const std::uint8_t> payload);
// layout nullopt: qt for a 58-byte answer, else xt.
Expected<LidarStatus> parse_lidar_status(std::span<const std::uint8_t> payload,
                                         std::optional<StatusLayout> layout);
Expected<PtpConfig> parse_ptp_config(std::span<const std::uint8_t> payload);

// What one round of questions got; a part is nullopt when the sensor did not answer it (a
// command its firmware lacks, PTP disabled).
struct ClockReplies {
  std::optional<PtpConfig> config;
  std::optional<LidarStatus> status;
  std::optional<PtpStatus> ptp;
  std::optional<PortDataSet> port;
  std::optional<TimeStatusNp> time_status;
  std::optional<GrandmasterSettingsNp> grandmaster;
};

// The reported half of a ClockStatus (source, state, domain, offset, path delay, grandmaster,
// UTC offset, timescale); the caller sets reported_ns. Whatever the values, never fails.
ClockStatus clock_status(const ClockReplies& replies);

}  // namespace sim::hesai::ptc
