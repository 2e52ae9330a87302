// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/diagnostics.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

#include "cdr.hpp"
#include "wire.hpp"

namespace sim::ros2 {

namespace {

#define SIM_ROS2_SEPARATOR \
  "================================================================================\n"

// diagnostic_msgs' .msg texts without their comments; nested types fully qualified for
// @foxglove/rosmsg, as in message.cpp.
constexpr std::string_view diagnostic_array_msg =
    "std_msgs/msg/Header header\n"
    "diagnostic_msgs/msg/DiagnosticStatus[] status\n" SIM_ROS2_SEPARATOR
    "MSG: std_msgs/msg/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n" SIM_ROS2_SEPARATOR
    "MSG: builtin_interfaces/msg/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n" SIM_ROS2_SEPARATOR
    "MSG: diagnostic_msgs/msg/DiagnosticStatus\n"
    "byte OK=0\n"
    "byte WARN=1\n"
    "byte ERROR=2\n"
    "byte STALE=3\n"
    "byte level\n"
    "string name\n"
    "string message\n"
    "string hardware_id\n"
    "diagnostic_msgs/msg/KeyValue[] values\n" SIM_ROS2_SEPARATOR
    "MSG: diagnostic_msgs/msg/KeyValue\n"
    "string key\n"
    "string value\n";

#undef SIM_ROS2_SEPARATOR

constexpr std::string_view kUnknown = "unknown";
constexpr std::string_view kNamePrefix = "sim: ";
constexpr std::string_view kNameSuffix = " clock";

// Why `text` cannot go into a CDR string here, if it cannot.
std::optional<Error> text_problem(std::string_view what, std::string_view text) {
  if (text.size() > max_diagnostic_text) {
    return wire::invalid("a diagnostic " + std::string(what) + " of " + std::to_string(text.size()) +
                         " bytes is longer than the " + std::to_string(max_diagnostic_text) +
                         " sent here");
  }
  if (text.find('\0') != std::string_view::npos) {
    return wire::invalid("a diagnostic " + std::string(what) + " contains a NUL character");
  }
  return std::nullopt;
}

std::optional<Error> array_problem(const DiagnosticArray& array, std::size_t& bound) {
  if (auto e = wire::header_problem(Header{array.stamp, array.frame_id})) return e;
  if (array.status.size() > max_diagnostic_statuses) {
    return wire::invalid("a DiagnosticArray of " + std::to_string(array.status.size()) +
                         " statuses has more than the " + std::to_string(max_diagnostic_statuses) +
                         " sent here");
  }
  bound = 32 + array.frame_id.size();
  for (const DiagnosticStatus& s : array.status) {
    if (s.values.size() > max_diagnostic_values) {
      return wire::invalid("the diagnostic status '" + s.name + "' has more than " +
                           std::to_string(max_diagnostic_values) + " values");
    }
    for (const auto* text : {&s.name, &s.message, &s.hardware_id}) {
      if (auto e = text_problem("text", *text)) return e;
      bound += text->size() + 12;
    }
    bound += 8;
    for (const KeyValue& kv : s.values) {
      if (auto e = text_problem("key", kv.key)) return e;
      if (auto e = text_problem("value", kv.value)) return e;
      bound += kv.key.size() + kv.value.size() + 24;
    }
  }
  return std::nullopt;
}

// The smallest a status takes on the wire (level, three empty strings, no values, aligned):
// a declared count beyond remaining / this cannot be true, so nothing that large is allocated.
constexpr std::size_t kMinStatusBytes = 20;
constexpr std::size_t kMinKeyValueBytes = 8;

std::string read_text(cdr::Reader& r, const char* what) { return std::string(r.string(what)); }

}  // namespace

const std::string* DiagnosticStatus::value(std::string_view key) const noexcept {
  for (const KeyValue& kv : values) {
    if (kv.key == key) return &kv.value;
  }
  return nullptr;
}

std::string_view diagnostic_array_schema() noexcept { return diagnostic_array_msg; }

Expected<std::vector<std::byte>> encode_diagnostic_array(const DiagnosticArray& array) {
  std::size_t bound = 0;
  if (auto e = array_problem(array, bound)) return *e;
  std::vector<std::byte> out(bound);
  cdr::Writer w(out);
  wire::write_header(w, Header{array.stamp, array.frame_id});
  w.u32(static_cast<std::uint32_t>(array.status.size()));
  for (const DiagnosticStatus& s : array.status) {
    w.u8(static_cast<std::uint8_t>(s.level));
    w.string(s.name);
    w.string(s.message);
    w.string(s.hardware_id);
    w.u32(static_cast<std::uint32_t>(s.values.size()));
    for (const KeyValue& kv : s.values) {
      w.string(kv.key);
      w.string(kv.value);
    }
  }
  out.resize(w.overflow() ? 0 : w.size());
  if (out.empty()) return wire::invalid("a DiagnosticArray did not fit the bytes computed for it");
  return out;
}

Expected<DiagnosticArray> decode_diagnostic_array(std::span<const std::byte> message) {
  cdr::Reader r(message);
  DiagnosticArray out;
  if (r.encapsulation()) {
    const Header header = wire::read_header(r);
    out.stamp = header.stamp;
    out.frame_id = std::string(header.frame_id);
    const std::uint32_t count = r.u32("status");
    if (r.ok() && (count > max_diagnostic_statuses || count > r.remaining() / kMinStatusBytes + 1)) {
      return wire::malformed(diagnostic_array_type_name,
                             "it declares " + std::to_string(count) +
                                 " statuses, more than it holds or than the " +
                                 std::to_string(max_diagnostic_statuses) + " accepted");
    }
    for (std::uint32_t i = 0; i < count && r.ok(); ++i) {
      DiagnosticStatus s;
      s.level = static_cast<DiagnosticLevel>(r.u8("status.level"));
      s.name = read_text(r, "status.name");
      s.message = read_text(r, "status.message");
      s.hardware_id = read_text(r, "status.hardware_id");
      const std::uint32_t values = r.u32("status.values");
      if (r.ok() && (values > max_diagnostic_values || values > r.remaining() / kMinKeyValueBytes)) {
        return wire::malformed(diagnostic_array_type_name,
                               "its status '" + s.name + "' declares " + std::to_string(values) +
                                   " values, more than it holds or than the " +
                                   std::to_string(max_diagnostic_values) + " accepted");
      }
      for (std::uint32_t v = 0; v < values && r.ok(); ++v) {
        KeyValue kv;
        kv.key = read_text(r, "status.values.key");
        kv.value = read_text(r, "status.values.value");
        s.values.push_back(std::move(kv));
      }
      if (r.ok()) out.status.push_back(std::move(s));
    }
  }
  if (!r.ok()) return wire::read_failure(diagnostic_array_type_name, r);
  if (auto e = wire::stamp_problem(diagnostic_array_type_name, Header{out.stamp, out.frame_id})) {
    return *e;
  }
  return out;
}

// --- A stream's clock.

namespace {

template <typename Int>
std::string number(Int v) {
  return std::to_string(v);
}

template <typename Int>
std::string optional_number(const std::optional<Int>& v) {
  return v ? std::to_string(*v) : std::string(kUnknown);
}

// The shortest text that reads back as the same double.
std::string exact(double v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

std::vector<KeyValue> clock_values(const ClockStatus& c) {
  return {
      {"clock_source", to_string(c.source)},
      {"sync_state", to_string(c.state)},
      {"offset_from_master_ns", optional_number(c.offset_from_master_ns)},
      {"grandmaster_id", c.grandmaster.empty() ? std::string(kUnknown) : c.grandmaster},
      {"offset_to_host_ns", optional_number(c.offset_to_host_ns)},
      {"spread_ns", number(c.spread_ns)},
      {"drift_ppm", exact(c.drift_ppm)},
      {"steps", number(c.steps)},
      {"tai_correction_ns", number(c.tai_correction_ns)},
      {"stamps", to_string(c.stamps)},
      {"verdict", to_string(c.verdict)},
      {"problem", c.problem},
      {"ptp_domain", c.ptp_domain < 0 ? std::string(kUnknown) : number(c.ptp_domain)},
      {"path_delay_ns", optional_number(c.path_delay_ns)},
      {"utc_offset_s", optional_number(c.utc_offset_s)},
      {"ptp_timescale", c.ptp_timescale ? "true" : "false"},
      {"last_step_ns", number(c.last_step_ns)},
      {"packets_measured", number(c.packets_measured)},
      {"reported_ns", number(c.reported_ns)},
      {"measured_ns", number(c.measured_ns)},
  };
}

}  // namespace

std::string clock_diagnostic_name(std::string_view stream) {
  return std::string(kNamePrefix) + std::string(stream) + std::string(kNameSuffix);
}

std::optional<std::string> stream_of_clock_diagnostic(std::string_view name) {
  if (name.size() <= kNamePrefix.size() + kNameSuffix.size() || !name.starts_with(kNamePrefix) ||
      !name.ends_with(kNameSuffix)) {
    return std::nullopt;
  }
  name.remove_prefix(kNamePrefix.size());
  name.remove_suffix(kNameSuffix.size());
  return std::string(name);
}

std::string clock_hardware_id(std::string_view stream, const std::optional<SensorInfo>& sensor) {
  if (sensor && !sensor->identity.serial.empty()) return sensor->identity.serial;
  return std::string(stream);
}

DiagnosticStatus clock_diagnostic(std::string_view stream, std::string_view hardware_id,
                                  const std::optional<ClockStatus>& clock, bool writer_alive) {
  DiagnosticStatus s;
  s.name = clock_diagnostic_name(stream);
  s.hardware_id = std::string(hardware_id);
  if (!clock) {
    s.level = DiagnosticLevel::stale;
    s.message = writer_alive ? "the writer of " + std::string(stream) + " reports no clock"
                             : "the writer of " + std::string(stream) + " stopped";
    return s;
  }
  s.values = clock_values(*clock);
  const std::string line = summary(*clock);
  const std::string& told = clock->problem.empty() ? line : clock->problem;
  if (!writer_alive) {
    s.level = DiagnosticLevel::stale;
    s.message = "the writer stopped; last clock: " + line;
    return s;
  }
  switch (clock->verdict) {
    case ClockVerdict::ok: s.level = DiagnosticLevel::ok; s.message = line; break;
    case ClockVerdict::warn: s.level = DiagnosticLevel::warn; s.message = told; break;
    case ClockVerdict::error: s.level = DiagnosticLevel::error; s.message = told; break;
    case ClockVerdict::unknown:
      s.level = DiagnosticLevel::ok;
      s.message = "clock not measured yet: " + line;
      break;
  }
  return s;
}

namespace {

// Reads the values of a clock status back, remembering the first key that does not parse.
class ValueReader {
 public:
  explicit ValueReader(const DiagnosticStatus& status) : status_(status) {}

  const std::string* find(const char* key) { return status_.value(key); }

  template <typename Int>
  void integer(const char* key, Int& out) {
    const std::string* v = find(key);
    if (v == nullptr) return;
    Int parsed{};
    const auto [end, ec] = std::from_chars(v->data(), v->data() + v->size(), parsed);
    if (ec != std::errc{} || end != v->data() + v->size()) return fail(key);
    out = parsed;
  }
  template <typename Int>
  void optional_integer(const char* key, std::optional<Int>& out) {
    const std::string* v = find(key);
    if (v == nullptr || *v == kUnknown) {
      out.reset();
      return;
    }
    Int parsed{};
    integer(key, parsed);
    out = parsed;
  }
  void real(const char* key, double& out) {
    const std::string* v = find(key);
    if (v == nullptr) return;
    double parsed = 0;
    const auto [end, ec] = std::from_chars(v->data(), v->data() + v->size(), parsed);
    if (ec != std::errc{} || end != v->data() + v->size() || !std::isfinite(parsed)) return fail(key);
    out = parsed;
  }
  // An enum by the name to_string() gives its values 0 … last.
  template <typename Enum>
  void name(const char* key, Enum& out, std::uint32_t last) {
    const std::string* v = find(key);
    if (v == nullptr) return;
    for (std::uint32_t i = 0; i <= last; ++i) {
      if (*v == to_string(static_cast<Enum>(i))) {
        out = static_cast<Enum>(i);
        return;
      }
    }
    fail(key);
  }
  void text(const char* key, std::string& out, bool unknown_is_empty) {
    const std::string* v = find(key);
    if (v == nullptr) return;
    out = unknown_is_empty && *v == kUnknown ? std::string{} : *v;
  }
  void boolean(const char* key, bool& out) {
    const std::string* v = find(key);
    if (v == nullptr) return;
    if (*v != "true" && *v != "false") return fail(key);
    out = *v == "true";
  }
  const char* failed() const { return failed_; }

 private:
  void fail(const char* key) {
    if (failed_ == nullptr) failed_ = key;
  }
  const DiagnosticStatus& status_;
  const char* failed_ = nullptr;
};

}  // namespace

Expected<ClockStatus> clock_from_diagnostic(const DiagnosticStatus& status) {
  if (status.value("clock_source") == nullptr || status.value("verdict") == nullptr) {
    return wire::invalid("the diagnostic status '" + status.name +
                         "' carries no clock record (no clock_source or verdict value)");
  }
  ClockStatus c;
  ValueReader r(status);
  r.name("clock_source", c.source, static_cast<std::uint32_t>(ClockSource::replayed));
  r.name("sync_state", c.state, static_cast<std::uint32_t>(ClockState::free_running));
  r.optional_integer("offset_from_master_ns", c.offset_from_master_ns);
  r.text("grandmaster_id", c.grandmaster, true);
  r.optional_integer("offset_to_host_ns", c.offset_to_host_ns);
  r.integer("spread_ns", c.spread_ns);
  r.real("drift_ppm", c.drift_ppm);
  r.integer("steps", c.steps);
  r.integer("tai_correction_ns", c.tai_correction_ns);
  r.name("stamps", c.stamps, static_cast<std::uint32_t>(StampClock::host_arrival));
  r.name("verdict", c.verdict, static_cast<std::uint32_t>(ClockVerdict::error));
  r.text("problem", c.problem, false);
  std::optional<std::int32_t> domain;
  r.optional_integer("ptp_domain", domain);
  c.ptp_domain = domain.value_or(-1);
  r.optional_integer("path_delay_ns", c.path_delay_ns);
  r.optional_integer("utc_offset_s", c.utc_offset_s);
  r.boolean("ptp_timescale", c.ptp_timescale);
  r.integer("last_step_ns", c.last_step_ns);
  r.integer("packets_measured", c.packets_measured);
  r.integer("reported_ns", c.reported_ns);
  r.integer("measured_ns", c.measured_ns);
  if (r.failed() != nullptr) {
    return wire::invalid("the diagnostic status '" + status.name + "' has a " + r.failed() +
                         " value that is not one a clock record holds");
  }
  return c;
}

}  // namespace sim::ros2
