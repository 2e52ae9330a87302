// SPDX-License-Identifier: Apache-2.0
#include "sim/sensor_info.hpp"

#include <cmath>
#include <cstdio>

#include "region.hpp"
#include "sensor_block.hpp"

namespace sim {

namespace {

using detail::SensorFault;

// How far a rotation's squared norm may be from 1: tf2's BufferCore accepts |q|^2 within 1e-2
// of 1 (QUATERNION_NORMALIZATION_TOLERANCE), so hand-typed "0.7071 0 0 0.7071" from a launch
// file or a bag is a rotation here too. The record stores it normalised (see normalised()).
constexpr double kUnitTolerance = 10e-3;

constexpr const char* kFrameFix =
    "use 1-63 printable ASCII characters without spaces, not starting with '/' (like \"lidar_top\")";

// The fault of a frame name as a phrase, or empty. The rule is tf2's (non-empty, no leading
// '/'), so frames from bags and ROS 2 peers ("camera-front", "os1.lidar", "3d_lidar") are
// accepted; in addition the name must fit the record and be printable ASCII without spaces,
// so every tool can print and quote it.
std::string frame_fault(std::string_view what, std::string_view frame) {
  std::string subject(what);  // built in place: GCC 12's -Wrestrict misfires on "\"" + string
  subject += " \"";
  subject += detail::printable(frame.substr(0, 80));
  subject += '"';
  if (frame.empty()) return std::string(what) + " is empty";
  if (frame.size() > SensorInfo::kMaxName) return subject + " is longer than 63 bytes";
  for (const char c : frame) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte <= 0x20 || byte >= 0x7f) {
      return subject + " holds a space, a control character or a byte outside ASCII";
    }
  }
  if (frame.front() == '/') return subject + " starts with '/', which tf2 refuses";
  return {};
}

// The length of the well-formed UTF-8 character at the start of `text` (1-4), or 0 when its
// first byte starts none (a stray continuation byte, an overlong form, a surrogate, past U+10FFFF,
// or cut short).
std::size_t utf8_length(std::string_view text) {
  const auto at = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = at(0);
  if (lead < 0x80) return 1;
  std::size_t n = 0;
  unsigned char low = 0x80, high = 0xBF;  // the range of the second byte
  if (lead >= 0xC2 && lead <= 0xDF) {
    n = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    n = 3;
    if (lead == 0xE0) low = 0xA0;
    if (lead == 0xED) high = 0x9F;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    n = 4;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (text.size() < n || at(1) < low || at(1) > high) return 0;
  for (std::size_t i = 2; i < n; ++i) {
    if ((at(i) & 0xC0) != 0x80) return 0;
  }
  return n;
}

// The fault of a free-text field (identity, calibration source, time sync), or empty.
std::string text_fault(std::string_view what, const std::string& text, std::size_t max) {
  if (text.size() > max) return std::string(what) + " is longer than " + std::to_string(max) + " bytes";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return std::string(what) + " holds a control character";
  }
  // Review turn 4 L6: every tool prints these, sim_ls --json too; JSON is UTF-8.
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_length(std::string_view(text).substr(i));
    if (n == 0) return std::string(what) + " holds bytes that are not UTF-8";
    i += n;
  }
  return {};
}

bool all_finite(const double* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i])) return false;
  }
  return true;
}

SensorFault mounting_fault(const Mounting& m) {
  const std::string fix = "give the mounting as finite metres and a unit quaternion (or roll, pitch, yaw)";
  if (!all_finite(m.translation.data(), 3)) return {"the mounting translation is not finite", fix};
  if (!all_finite(m.rotation.data(), 4)) return {"the mounting rotation is not finite", fix};
  const auto& q = m.rotation;
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (!(std::fabs(norm2 - 1.0) < kUnitTolerance)) {
    char text[112];
    std::snprintf(text, sizeof text, "the mounting rotation is not a unit quaternion (norm %.9g)",
                  std::sqrt(norm2));
    return {text, fix};
  }
  return {};
}

SensorFault calibration_fault(const CameraCalibration& c) {
  const std::string fix = "check the camera calibration file";
  if (c.width == 0 || c.height == 0) return {"the calibration's image size is 0", fix};
  if (std::string f = text_fault("the calibration's camera_name", c.camera_name, SensorInfo::kMaxName);
      !f.empty()) {
    return {f, fix};
  }
  if (c.distortion_model.empty()) return {"the calibration has no distortion_model", fix};
  if (std::string f = frame_fault("the calibration's distortion_model", c.distortion_model); !f.empty()) {
    return {f, fix};
  }
  if (c.d.size() > CameraCalibration::kMaxDistortion) {
    return {"the calibration has " + std::to_string(c.d.size()) + " distortion coefficients (at most " +
                std::to_string(CameraCalibration::kMaxDistortion) + ")",
            fix};
  }
  if (!all_finite(c.d.data(), c.d.size()) || !all_finite(c.k.data(), 9) || !all_finite(c.r.data(), 9) ||
      !all_finite(c.p.data(), 12)) {
    return {"a number of the calibration is not finite", fix};
  }
  if (!(c.k[0] > 0.0) || !(c.k[4] > 0.0)) return {"the calibration's K has a focal length of 0 or less", fix};
  const auto& roi = c.roi;
  if (std::uint64_t{roi.x_offset} + roi.width > c.width ||
      std::uint64_t{roi.y_offset} + roi.height > c.height) {
    return {"the calibration's region of interest lies outside its " + std::to_string(c.width) + "x" +
                std::to_string(c.height) + " image",
            fix};
  }
  return {};
}

}  // namespace

SensorFault detail::sensor_info_fault(const SensorInfo& info) {
  if (std::string f = frame_fault("frame_id", info.frame_id); !f.empty()) return {f, kFrameFix};
  if (std::string f = frame_fault("parent_frame", info.parent_frame); !f.empty()) return {f, kFrameFix};
  if (info.frame_id == info.parent_frame) {
    return {"frame_id and parent_frame are both \"" + info.frame_id + "\"",
            "give the sensor a frame of its own"};
  }
  const std::pair<const char*, const std::string*> names[] = {
      {"the vendor", &info.identity.vendor}, {"the model", &info.identity.model},
      {"the serial", &info.identity.serial}, {"the firmware", &info.identity.firmware}};
  for (const auto& [what, text] : names) {
    if (std::string f = text_fault(what, *text, SensorInfo::kMaxName); !f.empty()) {
      return {f, "shorten it to printable text"};
    }
  }
  if (std::string f = text_fault("the calibration_source", info.calibration_source, SensorInfo::kMaxSource);
      !f.empty()) {
    return {f, "shorten it to printable text"};
  }
  if (std::string f = text_fault("the time_sync", info.time_sync, SensorInfo::kMaxSource); !f.empty()) {
    return {f, "shorten it to printable text"};
  }
  if (static_cast<std::uint32_t>(info.time_base) > static_cast<std::uint32_t>(TimeBase::sensor_free_running)) {
    return {"the time_base is not a known TimeBase", "use one of sim::TimeBase"};
  }
  if (static_cast<std::uint32_t>(info.point_time) > static_cast<std::uint32_t>(PointTime::after_frame_stamp)) {
    return {"the point_time is not a known PointTime", "use one of sim::PointTime"};
  }
  if (info.mounting) {
    if (SensorFault f = mounting_fault(*info.mounting); !f.empty()) return f;
  }
  if (info.calibration) {
    if (SensorFault f = calibration_fault(*info.calibration); !f.empty()) return f;
  }
  return {};
}

std::string sensor_info_problem(const SensorInfo& info) {
  const SensorFault f = detail::sensor_info_fault(info);
  if (f.empty()) return {};
  return "the sensor description cannot be used: " + f.fault + "; " + f.fix;
}

std::string sensor_text(std::string_view text, std::size_t max_bytes) {
  std::string out(text.substr(0, max_bytes));
  if (out.size() < text.size()) {
    // Cut before a character the limit split: back over its continuation bytes (10xxxxxx) to
    // its lead byte, which goes too.
    std::size_t end = out.size();
    while (end > 0 && (static_cast<unsigned char>(out[end - 1]) & 0xC0) == 0x80) --end;
    if (end > 0 && static_cast<unsigned char>(out[end - 1]) >= 0xC0) {
      const auto lead = static_cast<unsigned char>(out[end - 1]);
      const std::size_t length = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : 2;
      if (out.size() - (end - 1) < length) out.resize(end - 1);
    }
  }
  for (std::size_t i = 0; i < out.size();) {
    const auto byte = static_cast<unsigned char>(out[i]);
    const std::size_t n = utf8_length(std::string_view(out).substr(i));
    if (n == 0 || byte < 0x20 || byte == 0x7f) {
      out[i] = '?';  // a control character, or a byte of no UTF-8 character (review turn 4 L6)
      ++i;
    } else {
      i += n;
    }
  }
  return out;
}

std::string drop_unusable_parts(SensorInfo& info) {
  std::string dropped;
  if (info.calibration && info.calibration->k[0] == 0.0) info.calibration.reset();  // uncalibrated
  if (info.calibration) {
    if (const SensorFault f = calibration_fault(*info.calibration); !f.empty()) {
      dropped = "its calibration is left out: " + f.fault;
      info.calibration.reset();
    }
  }
  if (info.mounting) {
    if (const SensorFault f = mounting_fault(*info.mounting); !f.empty()) {
      dropped += std::string(dropped.empty() ? "" : "; ") + "its mounting is left out: " + f.fault;
      info.mounting.reset();
    }
  }
  return dropped;
}

std::string frame_id_problem(std::string_view frame) {
  const std::string fault = frame_fault("frame name", frame);
  if (fault.empty()) return {};
  return fault + "; " + kFrameFix;
}

Mounting Mounting::from_xyz_rpy(double x, double y, double z, double roll, double pitch,
                                double yaw) noexcept {
  // tf2::Quaternion::setRPY: rotation about the fixed axes x (roll), y (pitch), z (yaw), in that
  // order, i.e. R = Rz(yaw) * Ry(pitch) * Rx(roll).
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  Mounting m;
  m.translation = {x, y, z};
  m.rotation = {sr * cp * cy - cr * sp * sy,   // x
                cr * sp * cy + sr * cp * sy,   // y
                cr * cp * sy - sr * sp * cy,   // z
                cr * cp * cy + sr * sp * sy};  // w
  return m;
}

const char* to_string(TimeBase base) noexcept {
  switch (base) {
    case TimeBase::unknown: return "unknown";
    case TimeBase::host: return "host";
    case TimeBase::sensor_synchronized: return "sensor_synchronized";
    case TimeBase::sensor_free_running: return "sensor_free_running";
  }
  return "invalid";
}

const char* to_string(PointTime meaning) noexcept {
  switch (meaning) {
    case PointTime::none: return "none";
    case PointTime::after_frame_stamp: return "after_frame_stamp";
  }
  return "invalid";
}

std::string summary(const CameraCalibration& c) {
  char text[160];
  std::snprintf(text, sizeof text, "%ux%u %s fx=%.1f fy=%.1f cx=%.1f cy=%.1f", c.width, c.height,
                detail::printable(c.distortion_model).c_str(), c.k[0], c.k[4], c.k[2], c.k[5]);
  return text;
}

bool operator==(const CameraCalibration::RegionOfInterest& a,
                const CameraCalibration::RegionOfInterest& b) noexcept {
  return a.x_offset == b.x_offset && a.y_offset == b.y_offset && a.height == b.height &&
         a.width == b.width && a.do_rectify == b.do_rectify;
}

bool operator==(const CameraCalibration& a, const CameraCalibration& b) noexcept {
  return a.width == b.width && a.height == b.height && a.camera_name == b.camera_name &&
         a.distortion_model == b.distortion_model && a.d == b.d && a.k == b.k && a.r == b.r &&
         a.p == b.p && a.binning_x == b.binning_x && a.binning_y == b.binning_y && a.roi == b.roi;
}

bool operator==(const SensorIdentity& a, const SensorIdentity& b) noexcept {
  return a.vendor == b.vendor && a.model == b.model && a.serial == b.serial && a.firmware == b.firmware;
}

bool operator==(const SensorInfo& a, const SensorInfo& b) noexcept {
  return a.frame_id == b.frame_id && a.parent_frame == b.parent_frame && a.mounting == b.mounting &&
         a.calibration == b.calibration && a.identity == b.identity &&
         a.calibration_source == b.calibration_source && a.time_base == b.time_base &&
         a.time_sync == b.time_sync && a.point_time == b.point_time;
}

}  // namespace sim
