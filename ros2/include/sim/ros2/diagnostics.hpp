// SPDX-License-Identifier: Apache-2.0
// diagnostic_msgs/msg/DiagnosticArray on /diagnostics: how each stream's clock (sim::ClockStatus)
// leaves the host. The DDS bridge publishes one status per stream about once a second, the
// Foxglove server offers the same channel (Foxglove's Diagnostics panels read it), and sim_record
// records each change of a stream's clock as one status, which sim_play turns back into the
// played stream's clock record. Same XCDR1 little-endian bytes as every message of this layer.
//
// One status per stream: name "sim: <stream> clock", hardware_id the sensor's serial (else the
// stream's name), level from the verdict, message the problem sentence (else the summary), and
// the record field by field as key/value pairs (docs/bridge.md, "Clock diagnostics"), so that
// clock_from_diagnostic() gives back the very record that was sent.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/result.hpp"
#include "sim/ros2/message.hpp"
#include "sim/sensor_info.hpp"

namespace sim::ros2 {

inline constexpr std::string_view diagnostic_array_type_name = "diagnostic_msgs/msg/DiagnosticArray";
inline constexpr std::string_view diagnostic_array_dds_type_name =
    "diagnostic_msgs::msg::dds_::DiagnosticArray_";
inline constexpr std::string_view diagnostics_topic = "/diagnostics";

// The ros2msg schema text (as ros2msg_schema() in message.hpp) for MCAP and Foxglove channels.
std::string_view diagnostic_array_schema() noexcept;

// diagnostic_msgs/msg/DiagnosticStatus's level constants (a byte on the wire).
enum class DiagnosticLevel : std::uint8_t { ok = 0, warn = 1, error = 2, stale = 3 };

struct KeyValue {
  std::string key;
  std::string value;
  friend bool operator==(const KeyValue&, const KeyValue&) = default;
};

struct DiagnosticStatus {
  DiagnosticLevel level = DiagnosticLevel::ok;
  std::string name;
  std::string message;
  std::string hardware_id;
  std::vector<KeyValue> values;
  friend bool operator==(const DiagnosticStatus&, const DiagnosticStatus&) = default;

  // The value of `key`, or nullptr.
  const std::string* value(std::string_view key) const noexcept;
};

struct DiagnosticArray {
  Time stamp{};
  std::string frame_id;  // diagnostic_updater leaves it empty
  std::vector<DiagnosticStatus> status;
};

// Most statuses one DiagnosticArray, key/value pairs one status, and bytes one text may hold here
// (a received message that declares more is dropped as malformed).
inline constexpr std::size_t max_diagnostic_statuses = 4096;
inline constexpr std::size_t max_diagnostic_values = 1024;
inline constexpr std::size_t max_diagnostic_text = 64 * 1024;

// An error for a text with a NUL character or longer than max_diagnostic_text, or too many
// statuses or values.
Expected<std::vector<std::byte>> encode_diagnostic_array(const DiagnosticArray& array);
Expected<DiagnosticArray> decode_diagnostic_array(std::span<const std::byte> message);

// --- A stream's clock as a DiagnosticStatus.

// "sim: /lidar_top clock", and back (nullopt for a status of anything else).
std::string clock_diagnostic_name(std::string_view stream);
std::optional<std::string> stream_of_clock_diagnostic(std::string_view name);

// The sensor's serial number when its description names one, else the stream's name.
std::string clock_hardware_id(std::string_view stream, const std::optional<SensorInfo>& sensor);

// The status of a stream's clock. Levels: verdict ok → OK; warn → WARN; error → ERROR; unknown
// → OK with the message "clock not measured yet: <summary>" (nothing says it is wrong, and a
// stream that just started is not a fault); a writer that stopped → STALE ("the writer stopped;
// last clock: …") with the last record's values; no record at all → STALE ("the writer of <stream>
// reports no clock") without values.
DiagnosticStatus clock_diagnostic(std::string_view stream, std::string_view hardware_id,
                                  const std::optional<ClockStatus>& clock, bool writer_alive);

// The record a clock_diagnostic() status carries (every field, reported_ns and measured_ns as
// sent). An error (one sentence) for a status without the clock's values or with a value that is
// not what the key holds.
Expected<ClockStatus> clock_from_diagnostic(const DiagnosticStatus& status);

}  // namespace sim::ros2
