// SPDX-License-Identifier: Apache-2.0
#include "sensor_block.hpp"

#include <sched.h>

#include <algorithm>
#include <cstring>
#include <string_view>

#include "shared_copy.hpp"
#include "sim/clock.hpp"

namespace sim::detail {

namespace {

// An update is a ~1 KiB copy: a block that stays in the middle of the same update this long
// belongs to a writer that stopped (died) there.
constexpr std::int64_t kStuckUpdateNs = 50'000'000;
// A reader gives up after this long if every copy overlapped another update (a writer changing
// its description without pause).
constexpr std::int64_t kMaxReadNs = 1'000'000'000;

template <std::size_t N>
void put(char (&field)[N], const std::string& text) noexcept {
  std::memset(field, 0, N);
  std::memcpy(field, text.data(), std::min(text.size(), N - 1));
}

// The string in a field, or a fault if it is not NUL-terminated and NUL-padded.
template <std::size_t N>
bool take(const char (&field)[N], std::string& out) {
  const void* end = std::memchr(field, '\0', N);
  if (end == nullptr) return false;
  const std::size_t length = static_cast<std::size_t>(static_cast<const char*>(end) - field);
  for (std::size_t i = length; i < N; ++i) {
    if (field[i] != '\0') return false;
  }
  out.assign(field, length);
  return true;
}

// The fields of a record as a SensorInfo, or the name of the first string field that is not a
// NUL-terminated string (empty on success).
std::string unpack_strings(const SensorRecord& r, SensorInfo& info) {
  struct Field {
    const char (*text)[kNameField];
    std::string* out;
    const char* name;
  };
  info.calibration.emplace();  // filled in here, dropped later when the record has none
  const Field names[] = {{&r.frame_id, &info.frame_id, "frame_id"},
                         {&r.parent_frame, &info.parent_frame, "parent_frame"},
                         {&r.vendor, &info.identity.vendor, "vendor"},
                         {&r.model, &info.identity.model, "model"},
                         {&r.serial, &info.identity.serial, "serial"},
                         {&r.firmware, &info.identity.firmware, "firmware"},
                         {&r.camera_name, &info.calibration->camera_name, "camera_name"},
                         {&r.distortion_model, &info.calibration->distortion_model,
                          "distortion_model"}};
  for (const Field& f : names) {
    if (!take(*f.text, *f.out)) return f.name;
  }
  if (!take(r.calibration_source, info.calibration_source)) return "calibration_source";
  if (!take(r.time_sync, info.time_sync)) return "time_sync";
  return {};
}

// The record as a SensorInfo, or a fault phrase for what is not a valid field.
std::string decode(const SensorRecord& r, SensorInfo& info) {
  if ((r.flags & ~kSensorKnownFlags) != 0 || r.reserved != 0) return "it uses flags this library does not know";
  if (r.time_base > static_cast<std::uint32_t>(TimeBase::sensor_free_running)) {
    return "its time base " + std::to_string(r.time_base) + " is unknown";
  }
  if (r.point_time > static_cast<std::uint32_t>(PointTime::after_frame_stamp)) {
    return "its point time " + std::to_string(r.point_time) + " is unknown";
  }
  if (const std::string bad = unpack_strings(r, info); !bad.empty()) {
    return "its " + bad + " is not a NUL-terminated string";
  }
  info.time_base = static_cast<TimeBase>(r.time_base);
  info.point_time = static_cast<PointTime>(r.point_time);
  if ((r.flags & kSensorHasMounting) != 0) {
    Mounting m;
    std::copy(std::begin(r.translation), std::end(r.translation), m.translation.begin());
    std::copy(std::begin(r.rotation), std::end(r.rotation), m.rotation.begin());
    info.mounting = m;
  }
  if ((r.flags & kSensorHasCalibration) == 0) {
    info.calibration.reset();
    return {};
  }
  if (r.distortion_count > CameraCalibration::kMaxDistortion) {
    return "it counts " + std::to_string(r.distortion_count) + " distortion coefficients (at most " +
           std::to_string(CameraCalibration::kMaxDistortion) + ")";
  }
  if (r.roi_do_rectify > 1) return "its roi.do_rectify is neither 0 nor 1";
  CameraCalibration& c = *info.calibration;
  c.width = r.width;
  c.height = r.height;
  c.d.assign(r.d, r.d + r.distortion_count);
  std::copy(std::begin(r.k), std::end(r.k), c.k.begin());
  std::copy(std::begin(r.r), std::end(r.r), c.r.begin());
  std::copy(std::begin(r.p), std::end(r.p), c.p.begin());
  c.binning_x = r.binning_x;
  c.binning_y = r.binning_y;
  c.roi = {r.roi_x_offset, r.roi_y_offset, r.roi_height, r.roi_width, r.roi_do_rectify != 0};
  return {};
}

Error damaged(const std::string& fault) {
  return Error{ErrorCode::region_invalid,
               "the stream's sensor description is damaged: " + fault + "; restart its writer"};
}

}  // namespace

SensorRecord to_record(const SensorInfo& info) noexcept {
  SensorRecord r;
  std::memset(&r, 0, sizeof r);  // every byte, padding too: readers compare records bytewise
  r.time_base = static_cast<std::uint32_t>(info.time_base);
  r.point_time = static_cast<std::uint32_t>(info.point_time);
  put(r.frame_id, info.frame_id);
  put(r.parent_frame, info.parent_frame);
  put(r.vendor, info.identity.vendor);
  put(r.model, info.identity.model);
  put(r.serial, info.identity.serial);
  put(r.firmware, info.identity.firmware);
  put(r.calibration_source, info.calibration_source);
  put(r.time_sync, info.time_sync);
  if (info.mounting) {
    r.flags |= kSensorHasMounting;
    std::copy(info.mounting->translation.begin(), info.mounting->translation.end(), r.translation);
    std::copy(info.mounting->rotation.begin(), info.mounting->rotation.end(), r.rotation);
  }
  if (const auto& c = info.calibration) {
    r.flags |= kSensorHasCalibration;
    r.width = c->width;
    r.height = c->height;
    put(r.camera_name, c->camera_name);
    put(r.distortion_model, c->distortion_model);
    r.distortion_count = static_cast<std::uint32_t>(std::min(c->d.size(), CameraCalibration::kMaxDistortion));
    std::copy_n(c->d.begin(), r.distortion_count, r.d);
    std::copy(c->k.begin(), c->k.end(), r.k);
    std::copy(c->r.begin(), c->r.end(), r.r);
    std::copy(c->p.begin(), c->p.end(), r.p);
    r.binning_x = c->binning_x;
    r.binning_y = c->binning_y;
    r.roi_x_offset = c->roi.x_offset;
    r.roi_y_offset = c->roi.y_offset;
    r.roi_height = c->roi.height;
    r.roi_width = c->roi.width;
    r.roi_do_rectify = c->roi.do_rectify ? 1 : 0;
  }
  return r;
}

void start_sensor_block(SensorBlock& block, std::uint64_t previous_word) noexcept {
  block.word.store(previous_word & ~(kSensorWriting | kSensorPresent), std::memory_order_relaxed);
}

void write_sensor_block(SensorBlock& block, const std::optional<SensorInfo>& info) noexcept {
  const SensorRecord record = info ? to_record(*info) : SensorRecord{};  // before: keep the window short
  const std::uint64_t old_word = block.word.load(std::memory_order_relaxed);
  const std::uint64_t generation_bits = old_word & ~(kSensorWriting | kSensorPresent);
  // Odd first, keeping the old presence: frames read meanwhile still carry the old generation.
  block.word.store(old_word | kSensorWriting, std::memory_order_relaxed);
  // Orders the mark before the record's stores (pairs with the readers' fence after their copy).
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(static_cast<void*>(&block.record), &record, sizeof record);
  block.word.store((generation_bits + kSensorGenerationStep) | (info ? kSensorPresent : 0),
                   std::memory_order_release);
}

Expected<std::optional<SensorInfo>> read_sensor_block(const SensorBlock& block,
                                                      std::uint64_t* generation) {
  SensorRecord record;
  const std::int64_t start = monotonic_ns();
  std::uint64_t odd_word = 0;  // the update the writer was in the middle of when first seen
  std::int64_t odd_since = 0;
  for (;;) {
    const std::uint64_t before = block.word.load(std::memory_order_acquire);
    if ((before & kSensorWriting) != 0) {  // the writer is in the middle of an update
      const std::int64_t now = monotonic_ns();
      if (before != odd_word) {
        odd_word = before;
        odd_since = now;
      } else if (now - odd_since > kStuckUpdateNs) {
        return damaged("its writer stopped in the middle of changing it");
      }
      sched_yield();
      continue;
    }
    if (monotonic_ns() - start > kMaxReadNs) {
      return Error{ErrorCode::system_error,
                   "the stream's sensor description changed during every attempt to read it; "
                   "try again"};
    }
    if (generation != nullptr) *generation = sensor_generation(before);
    if ((before & kSensorPresent) == 0) return std::optional<SensorInfo>{};
    copy_from_shared(&record, &block.record, sizeof record);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (block.word.load(std::memory_order_relaxed) != before) continue;

    if (sensor_generation(before) == 0) return damaged("it is marked present in generation 0");
    SensorInfo info;
    if (const std::string fault = decode(record, info); !fault.empty()) return damaged(fault);
    if (const SensorFault fault = sensor_info_fault(info); !fault.empty()) return damaged(fault.fault);
    // Every byte outside the fields in use must be zero, as the writer leaves it.
    const SensorRecord canonical = to_record(info);
    if (std::memcmp(&canonical, &record, sizeof record) != 0) {
      return damaged("it holds bytes outside its fields");
    }
    return std::optional<SensorInfo>{std::move(info)};
  }
}

}  // namespace sim::detail
