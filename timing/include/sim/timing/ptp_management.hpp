// SPDX-License-Identifier: Apache-2.0
// The linuxptp management messages a pmc-like client needs (IEEE 1588 §15, as ptp4l speaks them
// on its Unix socket): a GET request, and a bounds-checked parser of ptp4l's responses, which are
// outside bytes. Layouts: linuxptp's msg.h, tlv.h and ds.h (docs/time.md, "Host clock").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/result.hpp"
#include "sim/span.hpp"

namespace sim::timing::ptp {

// The management ids read by the host clock reader.
enum class ManagementId : std::uint16_t {
  default_data_set = 0x2000,          // clockIdentity, domainNumber
  current_data_set = 0x2001,          // offsetFromMaster, meanPathDelay
  parent_data_set = 0x2002,           // grandmasterIdentity
  time_properties_data_set = 0x2003,  // currentUtcOffset, utcOffsetValid, ptpTimescale
  port_data_set = 0x2004,             // portState (one response per port)
  time_status_np = 0xC000,            // master_offset, gmPresent, gmIdentity (linuxptp's own)
};

// IEEE 1588 port states, and linuxptp's GRAND_MASTER (10).
enum class PortState : std::uint8_t {
  initializing = 1,
  faulty = 2,
  disabled = 3,
  listening = 4,
  pre_master = 5,
  master = 6,
  passive = 7,
  uncalibrated = 8,
  slave = 9,
  grand_master = 10,
};
// As pmc prints it: "SLAVE", "UNCALIBRATED", …; "unknown state N" out of range is never returned:
// the parser rejects it.
const char* to_string(PortState state) noexcept;

using ClockIdentity = std::array<std::uint8_t, 8>;
// "xxxxxx.xxxx.xxxxxx", as ptp4l and pmc print a clock identity.
std::string format_clock_identity(const ClockIdentity& identity);

struct DefaultDataSet {
  ClockIdentity clock_identity{};
  std::uint8_t domain = 0;
  std::uint16_t number_ports = 0;
  bool slave_only = false;
};
struct CurrentDataSet {
  std::uint16_t steps_removed = 0;
  std::int64_t offset_from_master_ns = 0;  // TimeInterval (ns × 2^16) rounded toward zero
  std::int64_t mean_path_delay_ns = 0;
};
struct ParentDataSet {
  ClockIdentity grandmaster{};
  ClockIdentity parent{};
};
struct TimePropertiesDataSet {
  std::int16_t current_utc_offset_s = 0;
  bool utc_offset_valid = false;
  bool ptp_timescale = false;
};
struct PortDataSet {
  ClockIdentity clock_identity{};
  std::uint16_t port_number = 0;
  PortState state = PortState::initializing;
};
struct TimeStatusNp {
  std::int64_t master_offset_ns = 0;
  bool gm_present = false;
  ClockIdentity gm_identity{};
};

// One GET request, as `pmc -u -b 0 -d domain -t transport_specific 'GET …'` sends it, to every
// port (targetPortIdentity all ones). ptp4l ignores a request whose domain or transportSpecific
// (1: IEEE 802.1AS) differs from its own.
struct Request {
  ManagementId id = ManagementId::default_data_set;
  std::uint16_t sequence = 0;
  std::uint8_t domain = 0;
  std::uint8_t transport_specific = 0;
  std::uint16_t source_port = 0;  // the client's port number (pmc: its pid)
};
std::vector<std::uint8_t> encode_get(const Request& request);

// One parsed response: its header and the one data set it carries (the one named by `id`).
struct Response {
  std::uint8_t transport_specific = 0;
  std::uint8_t domain = 0;
  std::uint16_t sequence = 0;
  ManagementId id = ManagementId::default_data_set;
  std::optional<std::uint16_t> error;  // MANAGEMENT_ERROR_STATUS: ptp4l refused the GET (its code)
  std::optional<DefaultDataSet> default_ds;
  std::optional<CurrentDataSet> current_ds;
  std::optional<ParentDataSet> parent_ds;
  std::optional<TimePropertiesDataSet> time_properties_ds;
  std::optional<PortDataSet> port_ds;
  std::optional<TimeStatusNp> time_status;
};

// A datagram from ptp4l's socket: a RESPONSE to one of the ids above, every length checked
// against the datagram and the message's own lengths. Anything else (another message type or
// action, an unknown id, a port state out of range, cut short) is an ErrorCode::invalid_argument
// sentence saying what is wrong.
Expected<Response> parse_response(sim::span<const std::uint8_t> datagram);

}  // namespace sim::timing::ptp
