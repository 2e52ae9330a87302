// SPDX-License-Identifier: Apache-2.0
#include "sensor_block.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string_view>

#include "fixed_text.hpp"
#include "seqlock_block.hpp"

namespace sim::detail {

namespace {

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
    if (!take_text(*f.text, *f.out)) return f.name;
  }
  if (!take_text(r.calibration_source, info.calibration_source)) return "calibration_source";
  if (!take_text(r.time_sync, info.time_sync)) return "time_sync";
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

// `q` divided by its norm, unless it is a unit quaternion to 1e-12 already: then it is kept bit
// for bit, so a stored rotation reads back equal and re-encodes to the same record (the readers'
// canonical check), and what a writer set reads back as set.
std::array<double, 4> normalised(const std::array<double, 4>& q) noexcept {
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (!(norm2 > 0.0) || std::fabs(norm2 - 1.0) <= 1e-12 || !std::isfinite(norm2)) return q;
  const double norm = std::sqrt(norm2);
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

// A fault phrase as the error read_block() turns into its "damaged" sentence.
Error fault_error(std::string fault) { return Error{ErrorCode::region_invalid, std::move(fault)}; }

}  // namespace

SensorRecord to_record(const SensorInfo& info) noexcept {
  SensorRecord r;
  std::memset(&r, 0, sizeof r);  // every byte, padding too: readers compare records bytewise
  r.time_base = static_cast<std::uint32_t>(info.time_base);
  r.point_time = static_cast<std::uint32_t>(info.point_time);
  put_text(r.frame_id, info.frame_id);
  put_text(r.parent_frame, info.parent_frame);
  put_text(r.vendor, info.identity.vendor);
  put_text(r.model, info.identity.model);
  put_text(r.serial, info.identity.serial);
  put_text(r.firmware, info.identity.firmware);
  put_text(r.calibration_source, info.calibration_source);
  put_text(r.time_sync, info.time_sync);
  if (info.mounting) {
    r.flags |= kSensorHasMounting;
    std::copy(info.mounting->translation.begin(), info.mounting->translation.end(), r.translation);
    const std::array<double, 4> q = normalised(info.mounting->rotation);
    std::copy(q.begin(), q.end(), r.rotation);
  }
  if (const auto& c = info.calibration) {
    r.flags |= kSensorHasCalibration;
    r.width = c->width;
    r.height = c->height;
    put_text(r.camera_name, c->camera_name);
    put_text(r.distortion_model, c->distortion_model);
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
  start_block(block.word, previous_word);
}

void write_sensor_block(SensorBlock& block, const std::optional<SensorInfo>& info) noexcept {
  // Built before the update: keep the window short. The rotation is stored normalised.
  const SensorRecord record = info ? to_record(*info) : SensorRecord{};
  write_block(block.word, block.record, record, info.has_value());
}

Expected<std::optional<SensorInfo>> read_sensor_block(const SensorBlock& block,
                                                      std::uint64_t* generation) {
  return read_block<SensorInfo>(
      block.word, block.record, "sensor description", generation,
      [](const SensorRecord& record) -> Expected<SensorInfo> {
        SensorInfo info;
        if (const std::string fault = decode(record, info); !fault.empty()) return fault_error(fault);
        if (const SensorFault fault = sensor_info_fault(info); !fault.empty()) {
          return fault_error(fault.fault);
        }
        // Every byte outside the fields in use must be zero, as the writer leaves it.
        const SensorRecord canonical = to_record(info);
        if (std::memcmp(&canonical, &record, sizeof record) != 0) {
          return fault_error("it holds bytes outside its fields");
        }
        return info;
      });
}

}  // namespace sim::detail
