// SPDX-License-Identifier: Apache-2.0
#include "sim/sim.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/sensor_info.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"

struct sim_writer {
  sim::Writer writer;
};
struct sim_reader {
  sim::Reader reader;
  std::uint64_t sensor_generation = 0;  // of the frame SIM_readData delivered last
  std::uint64_t clock_generation = 0;   // likewise
  sim::StampClock stamp_clock = sim::StampClock::unknown;
};
struct sim_waitset {
  sim::Wakeup wakeup;  // SIM_waitsetWake's; the set watches it
  sim::WaitSet set;
};
struct sim_notifier {
  sim::StreamNotifier notifier;
};

namespace {

// One fixed buffer per thread, so the pointer SIM_lastError returns never dangles.
thread_local char last_error[512];

void set_last_error(const std::string& message) {
  const std::size_t n = std::min(message.size(), sizeof last_error - 1);
  std::memcpy(last_error, message.data(), n);
  last_error[n] = '\0';
}
void clear_last_error() { last_error[0] = '\0'; }

int fail(int code, const std::string& message) {
  set_last_error(message);
  return code;
}

sim_reader* open_reader(const char* name, size_t capacity, const sim::Trust& trust) {
  if (name == nullptr) {
    fail(SIM_EINVAL, "SIM_readerInit needs a stream name");
    return nullptr;
  }
  sim::ReaderOptions options;
  options.trust = trust;
  auto reader = sim::Reader::open(name, options);
  if (!reader) {
    fail(SIM_EINVAL, reader.error().message);
    return nullptr;
  }
  if (capacity != 0 && reader->capacity() > capacity) {
    fail(SIM_EINVAL, std::string("stream ") + name + " carries frames of up to " +
                         std::to_string(reader->capacity()) + " bytes but the reader was given " +
                         std::to_string(capacity) + "; pass at least that");
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_reader{std::move(*reader)};
}

int code_of(sim::ReadStatus status) {
  switch (status) {
    case sim::ReadStatus::new_frame:
    case sim::ReadStatus::no_new_frame: return 0;
    case sim::ReadStatus::writer_gone: return SIM_EWRITERGONE;
    case sim::ReadStatus::stale: return SIM_ESTALE;
    case sim::ReadStatus::checksum_mismatch: return SIM_ECHECKSUM;
    case sim::ReadStatus::buffer_too_small: return SIM_EBUFFER;
    case sim::ReadStatus::overrun: return SIM_EOVERRUN;
    case sim::ReadStatus::region_invalid: return SIM_EREGION;
  }
  return SIM_EINVAL;
}

std::string describe(const sim_reader* r, sim::ReadStatus status) {
  const std::string& name = r->reader.name();
  switch (status) {
    case sim::ReadStatus::writer_gone: return "the writer of " + name + " is gone";
    case sim::ReadStatus::stale: return "the newest frame of " + name + " is stale";
    case sim::ReadStatus::checksum_mismatch:
      return "the newest frame of " + name + " failed its checksum and was dropped";
    case sim::ReadStatus::buffer_too_small:
      return "the buffer is smaller than the newest frame of " + name + "; pass at least " +
             std::to_string(r->reader.capacity()) + " bytes";
    case sim::ReadStatus::overrun:
      return "the writer of " + name + " overwrote every copy attempt; read again";
    case sim::ReadStatus::region_invalid:
      return "the region of " + name + " failed validation; restart its writer";
    default: return {};
  }
}

template <std::size_t N>
void put_text(char (&out)[N], const std::string& text) {
  std::memset(out, 0, N);
  std::memcpy(out, text.data(), std::min(text.size(), N - 1));
}

// The text of a C field, or nullopt when it has no NUL within its array.
template <std::size_t N>
std::optional<std::string> take_text(const char (&in)[N]) {
  const void* end = std::memchr(in, '\0', N);
  if (end == nullptr) return std::nullopt;
  return std::string(in, static_cast<const char*>(end));
}

template <typename T>
void put_optional(int& has, T& value, const std::optional<T>& from) {
  has = from ? 1 : 0;
  value = from.value_or(T{});
}
template <typename T>
std::optional<T> take_optional(int has, T value) {
  return has != 0 ? std::optional<T>(value) : std::nullopt;
}

void to_c(const sim::ClockStatus& c, sim_clock_status& out) {
  out = sim_clock_status{};
  out.source = static_cast<int>(c.source);
  out.state = static_cast<int>(c.state);
  out.ptp_domain = c.ptp_domain;
  put_optional(out.has_offset_from_master, out.offset_from_master_ns, c.offset_from_master_ns);
  put_optional(out.has_path_delay, out.path_delay_ns, c.path_delay_ns);
  put_optional(out.has_utc_offset, out.utc_offset_s, c.utc_offset_s);
  put_optional(out.has_offset_to_host, out.offset_to_host_ns, c.offset_to_host_ns);
  put_text(out.grandmaster, c.grandmaster);
  out.ptp_timescale = c.ptp_timescale ? 1 : 0;
  out.tai_correction_ns = c.tai_correction_ns;
  out.reported_ns = c.reported_ns;
  out.spread_ns = c.spread_ns;
  out.drift_ppm = c.drift_ppm;
  out.steps = c.steps;
  out.last_step_ns = c.last_step_ns;
  out.packets_measured = c.packets_measured;
  out.measured_ns = c.measured_ns;
  out.verdict = static_cast<int>(c.verdict);
  put_text(out.problem, c.problem);
  out.stamps = static_cast<int>(c.stamps);
}

// The record of a C struct; the enums are checked by Writer::set_clock (clock_status_problem).
std::string from_c(const sim_clock_status& in, sim::ClockStatus& c) {
  const auto grandmaster = take_text(in.grandmaster);
  const auto problem = take_text(in.problem);
  if (!grandmaster) return "the clock's grandmaster is not NUL-terminated";
  if (!problem) return "the clock's problem is not NUL-terminated";
  const auto enum_value = [](int v) { return static_cast<std::uint32_t>(v < 0 ? 0x7fffffff : v); };
  c.source = static_cast<sim::ClockSource>(enum_value(in.source));
  c.state = static_cast<sim::ClockState>(enum_value(in.state));
  c.ptp_domain = in.ptp_domain;
  c.offset_from_master_ns = take_optional(in.has_offset_from_master, in.offset_from_master_ns);
  c.path_delay_ns = take_optional(in.has_path_delay, in.path_delay_ns);
  c.utc_offset_s = take_optional(in.has_utc_offset, in.utc_offset_s);
  c.offset_to_host_ns = take_optional(in.has_offset_to_host, in.offset_to_host_ns);
  c.grandmaster = *grandmaster;
  c.ptp_timescale = in.ptp_timescale != 0;
  c.tai_correction_ns = in.tai_correction_ns;
  c.reported_ns = in.reported_ns;
  c.spread_ns = in.spread_ns;
  c.drift_ppm = in.drift_ppm;
  c.steps = in.steps;
  c.last_step_ns = in.last_step_ns;
  c.packets_measured = in.packets_measured;
  c.measured_ns = in.measured_ns;
  c.verdict = static_cast<sim::ClockVerdict>(enum_value(in.verdict));
  c.problem = *problem;
  c.stamps = static_cast<sim::StampClock>(enum_value(in.stamps));
  return {};
}

void to_c(const sim::CameraCalibration& c, sim_camera_calibration& out) {
  out.width = c.width;
  out.height = c.height;
  put_text(out.camera_name, c.camera_name);
  put_text(out.distortion_model, c.distortion_model);
  out.distortion_count = static_cast<uint32_t>(std::min<std::size_t>(c.d.size(), SIM_DISTORTION_MAX));
  std::copy_n(c.d.begin(), out.distortion_count, out.d);
  std::copy(c.k.begin(), c.k.end(), out.k);
  std::copy(c.r.begin(), c.r.end(), out.r);
  std::copy(c.p.begin(), c.p.end(), out.p);
  out.binning_x = c.binning_x;
  out.binning_y = c.binning_y;
  out.roi_x_offset = c.roi.x_offset;
  out.roi_y_offset = c.roi.y_offset;
  out.roi_height = c.roi.height;
  out.roi_width = c.roi.width;
  out.roi_do_rectify = c.roi.do_rectify ? 1 : 0;
}

void to_c(const sim::SensorInfo& info, sim_sensor_info& out) {
  std::memset(&out, 0, sizeof out);
  put_text(out.frame_id, info.frame_id);
  put_text(out.parent_frame, info.parent_frame);
  if (info.mounting) {
    out.has_mounting = 1;
    std::copy(info.mounting->translation.begin(), info.mounting->translation.end(), out.translation);
    std::copy(info.mounting->rotation.begin(), info.mounting->rotation.end(), out.rotation);
  }
  if (info.calibration) {
    out.has_calibration = 1;
    to_c(*info.calibration, out.calibration);
  }
  put_text(out.vendor, info.identity.vendor);
  put_text(out.model, info.identity.model);
  put_text(out.serial, info.identity.serial);
  put_text(out.firmware, info.identity.firmware);
  put_text(out.calibration_source, info.calibration_source);
  out.time_base = static_cast<int>(info.time_base);
  put_text(out.time_sync, info.time_sync);
  out.point_time = static_cast<int>(info.point_time);
}

// The C description as a SensorInfo, or a sentence naming the field that is not a C string or
// holds an impossible count or enum (the rest is sensor_info_problem's to judge).
std::string from_c(const sim_sensor_info& in, sim::SensorInfo& out) {
  struct Field {
    std::optional<std::string> text;
    std::string* into;
    const char* name;
  };
  Field fields[] = {{take_text(in.frame_id), &out.frame_id, "frame_id"},
                    {take_text(in.parent_frame), &out.parent_frame, "parent_frame"},
                    {take_text(in.vendor), &out.identity.vendor, "vendor"},
                    {take_text(in.model), &out.identity.model, "model"},
                    {take_text(in.serial), &out.identity.serial, "serial"},
                    {take_text(in.firmware), &out.identity.firmware, "firmware"},
                    {take_text(in.calibration_source), &out.calibration_source, "calibration_source"},
                    {take_text(in.time_sync), &out.time_sync, "time_sync"}};
  for (Field& f : fields) {
    if (!f.text) return std::string("the sensor description's ") + f.name + " has no NUL within its array";
    *f.into = std::move(*f.text);
  }
  if (in.time_base < 0 || in.time_base > SIM_TIME_BASE_SENSOR_FREE_RUNNING) {
    return "the sensor description's time_base is not a SIM_TIME_BASE_* value";
  }
  if (in.point_time < 0 || in.point_time > SIM_POINT_TIME_AFTER_FRAME_STAMP) {
    return "the sensor description's point_time is not a SIM_POINT_TIME_* value";
  }
  out.time_base = static_cast<sim::TimeBase>(in.time_base);
  out.point_time = static_cast<sim::PointTime>(in.point_time);
  if (in.has_mounting != 0) {
    sim::Mounting m;
    std::copy(std::begin(in.translation), std::end(in.translation), m.translation.begin());
    std::copy(std::begin(in.rotation), std::end(in.rotation), m.rotation.begin());
    out.mounting = m;
  }
  if (in.has_calibration == 0) return {};
  const sim_camera_calibration& c = in.calibration;
  auto name = take_text(c.camera_name);
  auto model = take_text(c.distortion_model);
  if (!name || !model) return "the calibration's camera_name or distortion_model has no NUL within its array";
  if (c.distortion_count > SIM_DISTORTION_MAX) {
    return "the calibration's distortion_count is more than SIM_DISTORTION_MAX (16)";
  }
  sim::CameraCalibration cal;
  cal.width = c.width;
  cal.height = c.height;
  cal.camera_name = std::move(*name);
  cal.distortion_model = std::move(*model);
  cal.d.assign(c.d, c.d + c.distortion_count);
  std::copy(std::begin(c.k), std::end(c.k), cal.k.begin());
  std::copy(std::begin(c.r), std::end(c.r), cal.r.begin());
  std::copy(std::begin(c.p), std::end(c.p), cal.p.begin());
  cal.binning_x = c.binning_x;
  cal.binning_y = c.binning_y;
  cal.roi = {c.roi_x_offset, c.roi_y_offset, c.roi_height, c.roi_width, c.roi_do_rectify != 0};
  out.calibration = std::move(cal);
  return {};
}

}  // namespace

extern "C" {

sim_writer* SIM_writerInit(const char* name, size_t capacity) {
  if (name == nullptr) {
    fail(SIM_EINVAL, "SIM_writerInit needs a stream name");
    return nullptr;
  }
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = capacity;
  auto writer = sim::Writer::create(spec);
  if (!writer) {
    fail(SIM_EINVAL, writer.error().message);
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_writer{std::move(*writer)};
}

int SIM_writeData(sim_writer* w, const void* data, size_t size) {
  if (w == nullptr || (data == nullptr && size != 0)) {
    return fail(SIM_EINVAL, "SIM_writeData needs a writer and data");
  }
  const auto status = w->writer.write(
      std::span<const std::byte>(static_cast<const std::byte*>(data), size), sim::realtime_ns());
  if (status == sim::WriteStatus::too_large) {
    return fail(SIM_ETOOLARGE, "a frame of " + std::to_string(size) + " bytes does not fit " +
                                   w->writer.name() + ", whose capacity is " +
                                   std::to_string(w->writer.capacity()) + " bytes");
  }
  clear_last_error();
  return 0;
}

void SIM_writerClose(sim_writer* w) { delete w; }

sim_reader* SIM_readerInit(const char* name, size_t capacity) {
  return open_reader(name, capacity, sim::Trust{});
}

sim_reader* SIM_readerInitTrusting(const char* name, size_t capacity, const char* trust_owner,
                                   const char* trust_group) {
  auto trust = sim::Trust::parse(trust_owner != nullptr ? trust_owner : "",
                                 trust_group != nullptr ? trust_group : "");
  if (!trust) {
    fail(SIM_EINVAL, trust.error().message);
    return nullptr;
  }
  return open_reader(name, capacity, *trust);
}

long long SIM_readData(sim_reader* r, void* buf, size_t size, sim_frame_info* info) {
  if (r == nullptr || buf == nullptr) return fail(SIM_EINVAL, "SIM_readData needs a reader and a buffer");
  sim::FrameInfo frame;
  const auto status = r->reader.read(std::span<std::byte>(static_cast<std::byte*>(buf), size), frame);
  if (info != nullptr) *info = sim_frame_info{};  // seq 0: nothing delivered
  if (status == sim::ReadStatus::new_frame) {
    if (info != nullptr) {
      *info = {frame.seq, frame.stamp_ns, frame.publish_ns, frame.size, frame.receive_ns};
    }
    r->sensor_generation = frame.sensor_generation;
    r->clock_generation = frame.clock_generation;
    r->stamp_clock = frame.stamp_clock;
    clear_last_error();
    return static_cast<long long>(frame.size);  // 0 for an empty frame: info->seq says it is one
  }
  const int code = code_of(status);
  if (code < 0) return fail(code, describe(r, status));
  clear_last_error();
  return 0;
}

int SIM_waitData(sim_reader* r, int timeout_ms) {
  if (r == nullptr) return fail(SIM_EINVAL, "SIM_waitData needs a reader");
  const auto timeout = timeout_ms < 0 ? sim::kForever
                                     : std::chrono::nanoseconds(std::chrono::milliseconds(timeout_ms));
  const auto status = r->reader.wait(timeout);
  clear_last_error();
  if (status == sim::ReadStatus::new_frame) return 1;
  const int code = code_of(status);
  if (code < 0) return fail(code, describe(r, status));
  return 0;
}

void SIM_readerClose(sim_reader* r) { delete r; }

int SIM_writerSetSensorInfo(sim_writer* w, const sim_sensor_info* info) {
  if (w == nullptr || info == nullptr) {
    return fail(SIM_EINVAL, "SIM_writerSetSensorInfo needs a writer and a description");
  }
  sim::SensorInfo description;
  if (const std::string problem = from_c(*info, description); !problem.empty()) {
    return fail(SIM_EINVAL, problem + "; terminate every string and use the SIM_* constants");
  }
  if (auto set = w->writer.set_sensor_info(description); !set) return fail(SIM_EINVAL, set.error().message);
  clear_last_error();
  return 0;
}

int SIM_readerSensorInfo(sim_reader* r, sim_sensor_info* out) {
  if (r == nullptr || out == nullptr) return fail(SIM_EINVAL, "SIM_readerSensorInfo needs a reader and a struct");
  auto info = r->reader.sensor_info();
  if (!info) return fail(SIM_EREGION, info.error().message);
  clear_last_error();
  if (!info->has_value()) {
    std::memset(out, 0, sizeof *out);
    return 0;
  }
  to_c(**info, *out);
  return 1;
}

uint64_t SIM_readerSensorGeneration(const sim_reader* r) { return r != nullptr ? r->sensor_generation : 0; }

int SIM_writerSetClock(sim_writer* w, const sim_clock_status* clock) {
  if (w == nullptr || clock == nullptr) return fail(SIM_EINVAL, "SIM_writerSetClock needs a writer and a clock");
  sim::ClockStatus status;
  if (const std::string problem = from_c(*clock, status); !problem.empty()) {
    return fail(SIM_EINVAL, problem + "; terminate every string");
  }
  if (auto set = w->writer.set_clock(status); !set) return fail(SIM_EINVAL, set.error().message);
  clear_last_error();
  return 0;
}

int SIM_readerClock(sim_reader* r, sim_clock_status* out) {
  if (r == nullptr || out == nullptr) return fail(SIM_EINVAL, "SIM_readerClock needs a reader and a struct");
  auto clock = r->reader.clock();
  if (!clock) return fail(SIM_EREGION, clock.error().message);
  clear_last_error();
  if (!clock->has_value()) {
    *out = sim_clock_status{};
    return 0;
  }
  to_c(**clock, *out);
  return 1;
}

uint64_t SIM_readerClockGeneration(const sim_reader* r) { return r != nullptr ? r->clock_generation : 0; }
int SIM_readerStampClock(const sim_reader* r) { return r != nullptr ? static_cast<int>(r->stamp_clock) : 0; }

int SIM_destroy(const char* name) {
  if (name == nullptr) return fail(SIM_EINVAL, "SIM_destroy needs a stream name");
  if (auto removed = sim::destroy(name); !removed) return fail(SIM_EINVAL, removed.error().message);
  clear_last_error();
  return 0;
}

const char* SIM_lastError(void) { return last_error; }

// --- waiting (issue 12) ---

int SIM_readerSetWaitMode(sim_reader* r, int mode) {
  if (r == nullptr) return fail(SIM_EINVAL, "SIM_readerSetWaitMode needs a reader");
  switch (mode) {
    case SIM_WAIT_BLOCK: r->reader.set_wait_mode(sim::WaitMode::block); break;
    case SIM_WAIT_POLL: r->reader.set_wait_mode(sim::WaitMode::poll); break;
    case SIM_WAIT_ADAPTIVE: r->reader.set_wait_mode(sim::WaitMode::adaptive); break;
    default:
      return fail(SIM_EINVAL, "wait mode " + std::to_string(mode) +
                                  " is unknown; use SIM_WAIT_BLOCK, SIM_WAIT_POLL or SIM_WAIT_ADAPTIVE");
  }
  clear_last_error();
  return 0;
}

sim_waitset* SIM_waitsetCreate(void) {
  clear_last_error();
  auto* ws = new (std::nothrow) sim_waitset;
  if (ws != nullptr) ws->set.watch(ws->wakeup);
  return ws;
}

int SIM_waitsetAdd(sim_waitset* ws, sim_reader* r) {
  if (ws == nullptr || r == nullptr) return fail(SIM_EINVAL, "SIM_waitsetAdd needs a wait set and a reader");
  auto index = ws->set.add(r->reader);
  if (!index) return fail(SIM_EINVAL, index.error().message);
  clear_last_error();
  return static_cast<int>(*index);
}

int SIM_waitsetWait(sim_waitset* ws, int timeout_ms) {
  if (ws == nullptr) return fail(SIM_EINVAL, "SIM_waitsetWait needs a wait set");
  const auto timeout = timeout_ms < 0 ? sim::kForever
                                     : std::chrono::nanoseconds(std::chrono::milliseconds(timeout_ms));
  clear_last_error();
  const auto ready = ws->set.wait(timeout);
  if (ready) return static_cast<int>(*ready);
  return ws->set.woken() ? SIM_EWOKEN : SIM_ETIMEDOUT;
}

int SIM_waitsetWake(sim_waitset* ws) {
  if (ws == nullptr) return fail(SIM_EINVAL, "SIM_waitsetWake needs a wait set");
  ws->wakeup.notify();
  return 0;
}

int SIM_waitsetReady(const sim_waitset* ws, int index) {
  if (ws == nullptr || index < 0) return 0;
  return ws->set.ready(static_cast<std::size_t>(index)) ? 1 : 0;
}

void SIM_waitsetClose(sim_waitset* ws) { delete ws; }

sim_notifier* SIM_notifierOpen(const char* const* names, size_t count) {
  if (names == nullptr || count == 0) {
    fail(SIM_EINVAL, "SIM_notifierOpen needs at least one stream name");
    return nullptr;
  }
  std::vector<std::string> list;
  for (size_t i = 0; i < count; ++i) {
    if (names[i] == nullptr) {
      fail(SIM_EINVAL, "SIM_notifierOpen was given a NULL stream name");
      return nullptr;
    }
    list.emplace_back(names[i]);
  }
  auto notifier = sim::StreamNotifier::open(list);
  if (!notifier) {
    fail(SIM_EINVAL, notifier.error().message);
    return nullptr;
  }
  clear_last_error();
  return new (std::nothrow) sim_notifier{std::move(*notifier)};
}

int SIM_notifierFd(const sim_notifier* n) {
  if (n == nullptr) return fail(SIM_EINVAL, "SIM_notifierFd needs a notifier");
  return n->notifier.fd();
}

int SIM_notifierDrain(sim_notifier* n, int* arrived, size_t count) {
  if (n == nullptr) return fail(SIM_EINVAL, "SIM_notifierDrain needs a notifier");
  const std::vector<bool> which = n->notifier.drain();
  int streams = 0;
  for (size_t i = 0; i < which.size(); ++i) {
    if (which[i]) ++streams;
    if (arrived != nullptr && i < count) arrived[i] = which[i] ? 1 : 0;
  }
  clear_last_error();
  return streams;
}

void SIM_notifierClose(sim_notifier* n) { delete n; }

}  // extern "C"
