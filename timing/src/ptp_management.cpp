// SPDX-License-Identifier: Apache-2.0
#include "sim/timing/ptp_management.hpp"

#include <cstdio>

namespace sim::timing::ptp {
namespace {

constexpr std::uint8_t kMessageTypeManagement = 0x0D;
constexpr std::uint8_t kVersionPtp = 2;
constexpr std::uint8_t kControlManagement = 0x04;
constexpr std::uint8_t kActionGet = 0;
constexpr std::uint8_t kActionResponse = 2;
constexpr std::uint16_t kTlvManagement = 0x0001;
constexpr std::uint16_t kTlvManagementErrorStatus = 0x0002;
constexpr std::size_t kManagementHeaderSize = 48;  // the PTP header (34) + target port, hops, action
constexpr std::size_t kTlvHeaderSize = 4;           // type, length

// A bounds-checked big-endian reader over one message: every read past the end sets `short_`
// and yields 0, so a cut-short datagram is noticed once, at the end.
class Bytes {
 public:
  explicit Bytes(sim::span<const std::uint8_t> data) : data_(data) {}
  bool has(std::size_t offset, std::size_t size) const noexcept {
    return offset <= data_.size() && size <= data_.size() - offset;
  }
  std::uint8_t u8(std::size_t at) const noexcept { return has(at, 1) ? data_[at] : 0; }
  std::uint16_t u16(std::size_t at) const noexcept {
    return static_cast<std::uint16_t>(u8(at) << 8 | u8(at + 1));
  }
  std::uint32_t u32(std::size_t at) const noexcept {
    return std::uint32_t{u16(at)} << 16 | u16(at + 2);
  }
  std::uint64_t u64(std::size_t at) const noexcept {
    return std::uint64_t{u32(at)} << 32 | u32(at + 4);
  }
  std::int64_t i64(std::size_t at) const noexcept { return static_cast<std::int64_t>(u64(at)); }
  ClockIdentity identity(std::size_t at) const noexcept {
    ClockIdentity id{};
    for (std::size_t i = 0; i < id.size(); ++i) id[i] = u8(at + i);
    return id;
  }
  std::size_t size() const noexcept { return data_.size(); }

 private:
  sim::span<const std::uint8_t> data_;
};

// TimeInterval is ns × 2^16: the nanoseconds, rounded toward zero (pmc prints value / 65536.0).
std::int64_t time_interval_ns(std::int64_t scaled) noexcept { return scaled / 65536; }

Error malformed(const std::string& what) {
  return Error{ErrorCode::invalid_argument,
               "ptp4l's management response " + what + "; check that the socket is ptp4l's"};
}

// The data set of `id` at `at` (`size` bytes of TLV data); nullopt-free: false when too short.
bool parse_data_set(const Bytes& b, std::size_t at, std::size_t size, Response& r) {
  const auto needs = [&](std::size_t n) { return size >= n && b.has(at, n); };
  switch (r.id) {
    case ManagementId::default_data_set:
      if (!needs(20)) return false;
      r.default_ds = DefaultDataSet{b.identity(at + 10), b.u8(at + 18), b.u16(at + 2),
                                    (b.u8(at) & 0x02) != 0};
      return true;
    case ManagementId::current_data_set:
      if (!needs(18)) return false;
      r.current_ds = CurrentDataSet{b.u16(at), time_interval_ns(b.i64(at + 2)),
                                    time_interval_ns(b.i64(at + 10))};
      return true;
    case ManagementId::parent_data_set:
      if (!needs(32)) return false;
      r.parent_ds = ParentDataSet{b.identity(at + 24), b.identity(at)};
      return true;
    case ManagementId::time_properties_data_set: {
      if (!needs(4)) return false;
      const std::uint8_t flags = b.u8(at + 2);
      r.time_properties_ds = TimePropertiesDataSet{static_cast<std::int16_t>(b.u16(at)),
                                                   (flags & 0x04) != 0, (flags & 0x08) != 0};
      return true;
    }
    case ManagementId::port_data_set:
      if (!needs(26)) return false;
      r.port_ds = PortDataSet{b.identity(at), b.u16(at + 8), static_cast<PortState>(b.u8(at + 10))};
      return true;
    case ManagementId::time_status_np:
      if (!needs(50)) return false;
      r.time_status = TimeStatusNp{b.i64(at), b.u32(at + 38) != 0, b.identity(at + 42)};
      return true;
  }
  return false;
}

bool known_id(std::uint16_t id) noexcept {
  switch (static_cast<ManagementId>(id)) {
    case ManagementId::default_data_set:
    case ManagementId::current_data_set:
    case ManagementId::parent_data_set:
    case ManagementId::time_properties_data_set:
    case ManagementId::port_data_set:
    case ManagementId::time_status_np:
      return true;
  }
  return false;
}

}  // namespace

const char* to_string(PortState state) noexcept {
  switch (state) {
    case PortState::initializing: return "INITIALIZING";
    case PortState::faulty: return "FAULTY";
    case PortState::disabled: return "DISABLED";
    case PortState::listening: return "LISTENING";
    case PortState::pre_master: return "PRE_MASTER";
    case PortState::master: return "MASTER";
    case PortState::passive: return "PASSIVE";
    case PortState::uncalibrated: return "UNCALIBRATED";
    case PortState::slave: return "SLAVE";
    case PortState::grand_master: return "GRAND_MASTER";
  }
  return "unknown";
}

std::string format_clock_identity(const ClockIdentity& id) {
  char text[24];
  std::snprintf(text, sizeof text, "%02x%02x%02x.%02x%02x.%02x%02x%02x", id[0], id[1], id[2], id[3],
                id[4], id[5], id[6], id[7]);
  return text;
}

std::vector<std::uint8_t> encode_get(const Request& request) {
  std::vector<std::uint8_t> m(kManagementHeaderSize + kTlvHeaderSize + 2, 0);
  const auto put16 = [&](std::size_t at, std::uint16_t v) {
    m[at] = static_cast<std::uint8_t>(v >> 8);
    m[at + 1] = static_cast<std::uint8_t>(v);
  };
  m[0] = static_cast<std::uint8_t>((request.transport_specific & 0x0F) << 4 | kMessageTypeManagement);
  m[1] = kVersionPtp;
  put16(2, static_cast<std::uint16_t>(m.size()));
  m[4] = request.domain;
  put16(28, request.source_port);  // sourcePortIdentity: clockIdentity 0, our port number
  put16(30, request.sequence);
  m[32] = kControlManagement;
  m[33] = 0x7F;                                    // logMessageInterval: none
  for (std::size_t i = 34; i < 44; ++i) m[i] = 0xFF;  // targetPortIdentity: every port
  m[44] = 0;                                       // startingBoundaryHops (-b 0)
  m[45] = 0;                                       // boundaryHops
  m[46] = kActionGet;
  put16(48, kTlvManagement);
  put16(50, 2);                                    // managementId only: a GET carries no data
  put16(52, static_cast<std::uint16_t>(request.id));
  return m;
}

Expected<Response> parse_response(sim::span<const std::uint8_t> datagram) {
  const Bytes b(datagram);
  if (b.size() < kManagementHeaderSize + kTlvHeaderSize + 2) {
    return malformed("is cut short (" + std::to_string(b.size()) + " bytes)");
  }
  if ((b.u8(0) & 0x0F) != kMessageTypeManagement || (b.u8(1) & 0x0F) != kVersionPtp) {
    return malformed("is not a PTP version 2 management message");
  }
  const std::size_t length = b.u16(2);
  if (length > b.size() || length < kManagementHeaderSize + kTlvHeaderSize + 2) {
    return malformed("says it is " + std::to_string(length) + " bytes long in a datagram of " +
                     std::to_string(b.size()));
  }
  if ((b.u8(46) & 0x0F) != kActionResponse) return malformed("is not a RESPONSE");
  Response r;
  r.transport_specific = static_cast<std::uint8_t>(b.u8(0) >> 4);
  r.domain = b.u8(4);
  r.sequence = b.u16(30);
  const std::uint16_t tlv_type = b.u16(kManagementHeaderSize);
  const std::size_t tlv_length = b.u16(kManagementHeaderSize + 2);
  const std::size_t tlv_data = kManagementHeaderSize + kTlvHeaderSize;
  if (tlv_length > length - tlv_data) return malformed("has a TLV longer than the message");
  if (tlv_type == kTlvManagementErrorStatus) {
    // managementErrorId u16, managementId u16, reserved, displayData.
    if (tlv_length < 4) return malformed("has a cut-short error status");
    const std::uint16_t id = b.u16(tlv_data + 2);
    if (!known_id(id)) return malformed("refuses an id that was not asked for");
    r.id = static_cast<ManagementId>(id);
    r.error = b.u16(tlv_data);
    return r;
  }
  if (tlv_type != kTlvManagement || tlv_length < 2) return malformed("has no management TLV");
  const std::uint16_t id = b.u16(tlv_data);
  if (!known_id(id)) return malformed("answers an id that was not asked for");
  r.id = static_cast<ManagementId>(id);
  if (!parse_data_set(b, tlv_data + 2, tlv_length - 2, r)) {
    return malformed("carries a data set that is cut short");
  }
  if (r.port_ds && (static_cast<int>(r.port_ds->state) < 1 || static_cast<int>(r.port_ds->state) > 10)) {
    return malformed("gives port state " + std::to_string(static_cast<int>(r.port_ds->state)) +
                     ", which is not one of IEEE 1588's");
  }
  return r;
}

}  // namespace sim::timing::ptp
