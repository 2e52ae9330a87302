// SPDX-License-Identifier: Apache-2.0
// What a stream says about the sensor that makes its frames: where the sensor is (its frame, the
// parent frame and the mounting transform), a camera's calibration, the unit's identity and the
// time base of its stamps. The writer sets it at creation (StreamSpec::sensor) and may change it
// at any time (Writer::set_sensor_info: a recalibration, a remount); readers get it with
// Reader::sensor_info() and notice a change through FrameInfo::sensor_generation without
// reopening. It lives in the region's header page, beside the frames: publishing and reading a
// frame cost nothing more for it. docs/protocol.md ("Sensor description") has the format.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/result.hpp"

namespace sim {

// Where the sensor sits: `child` (the sensor's frame) in `parent`, as ROS 2's
// geometry_msgs/Transform: translation in metres, rotation a unit quaternion (x, y, z, w).
struct Mounting {
  std::array<double, 3> translation{0.0, 0.0, 0.0};
  std::array<double, 4> rotation{0.0, 0.0, 0.0, 1.0};  // x, y, z, w

  // From static_transform_publisher's --x --y --z --roll --pitch --yaw (metres, radians; the
  // rotation is yaw about z, then pitch about y, then roll about x, as tf2's setRPY).
  static Mounting from_xyz_rpy(double x, double y, double z, double roll, double pitch,
                               double yaw) noexcept;
  friend bool operator==(const Mounting& a, const Mounting& b) noexcept {
    return a.translation == b.translation && a.rotation == b.rotation;
  }
  friend bool operator!=(const Mounting& a, const Mounting& b) noexcept { return !(a == b); }
};

// A camera's intrinsic calibration: everything sensor_msgs/CameraInfo and the
// camera_calibration_parsers YAML hold. Matrices are row-major.
struct CameraCalibration {
  static constexpr std::size_t kMaxDistortion = 16;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::string camera_name{};                 // "" when the file had none
  std::string distortion_model = "plumb_bob";  // plumb_bob, rational_polynomial, equidistant, …
  std::vector<double> d{};                   // at most kMaxDistortion coefficients
  std::array<double, 9> k{};
  std::array<double, 9> r{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 12> p{};
  std::uint32_t binning_x = 0;
  std::uint32_t binning_y = 0;
  struct RegionOfInterest {
    std::uint32_t x_offset = 0, y_offset = 0, height = 0, width = 0;
    bool do_rectify = false;
  } roi{};
};

// Which clock the stream's stamps (FrameInfo::stamp_ns) are in.
enum class TimeBase : std::uint32_t {
  unknown = 0,
  host = 1,                  // the host's CLOCK_REALTIME when the data arrived
  sensor_synchronized = 2,   // the sensor's clock, synchronised (PTP/gPTP, PPS + NMEA) to UTC
  sensor_free_running = 3,   // the sensor's own clock, not synchronised to anything
};
const char* to_string(TimeBase base) noexcept;  // "unknown", "host", "sensor_synchronized", …

// What a LiDAR point's time (LidarPoint::time_offset_ns) means.
enum class PointTime : std::uint32_t {
  none = 0,               // points carry no time of their own (cameras, or unknown)
  after_frame_stamp = 1,  // ns after the frame's stamp_ns, which is the frame's first firing
};
const char* to_string(PointTime meaning) noexcept;

// The unit that makes the stream, where its driver can ask it (Hesai PTC, Aravis device info,
// V4L2 card and bus). Empty strings are unknown.
struct SensorIdentity {
  std::string vendor{};
  std::string model{};
  std::string serial{};
  std::string firmware{};
};

struct SensorInfo {
  static constexpr std::size_t kMaxName = 63;     // frame names and identity strings, bytes
  static constexpr std::size_t kMaxSource = 127;  // calibration_source and time_sync, bytes

  std::string frame_id{};                 // the sensor's frame, e.g. "camera_front_optical"
  std::string parent_frame = "base_link";
  std::optional<Mounting> mounting{};     // empty: the mounting is not known
  std::optional<CameraCalibration> calibration{};  // cameras with a calibration only
  SensorIdentity identity{};
  std::string calibration_source{};       // "file:///etc/cam.yaml", "sensor (PTC)", …
  TimeBase time_base = TimeBase::unknown;
  std::string time_sync{};                // the synchronisation state in words: "PTP locked", …
  PointTime point_time = PointTime::none;
};

// Field-by-field equality (spelled out: the public headers are C++17, which has no defaulted ==).
bool operator==(const CameraCalibration::RegionOfInterest& a,
                const CameraCalibration::RegionOfInterest& b) noexcept;
bool operator==(const CameraCalibration& a, const CameraCalibration& b) noexcept;
bool operator==(const SensorIdentity& a, const SensorIdentity& b) noexcept;
bool operator==(const SensorInfo& a, const SensorInfo& b) noexcept;
inline bool operator!=(const SensorInfo& a, const SensorInfo& b) noexcept { return !(a == b); }

// One sentence saying what is wrong with `info` (a frame name that is not a ROS 2 frame name, a
// string too long for the region, a non-finite number, a rotation that is not a unit quaternion
// within tf2's tolerance (|q|^2 within 1e-2 of 1; stored normalised),
// too many distortion coefficients, a K with zero focal length…), or empty when it can be stored.
std::string sensor_info_problem(const SensorInfo& info);

// For a description built from someone else's data (a bag's CameraInfo and /tf_static, a ROS 2
// peer): removes the parts sensor_info_problem would refuse, so one bad part does not take the
// others with it. A calibration ROS calls uncalibrated (K[0] = 0, as camera drivers publish
// without a calibration file) goes without a word; a calibration or mounting that is wrong goes
// and is named in the returned sentence (empty when nothing wrong was removed). What is left
// may still be refused (a frame name): check it with sensor_info_problem.
std::string drop_unusable_parts(SensorInfo& info);

// Empty if `frame` is a valid frame name: what tf2 accepts (not empty, not starting with '/'),
// in 1–63 bytes of printable ASCII without spaces ("camera-front", "os1.lidar", "3d_lidar").
std::string frame_id_problem(std::string_view frame);

// Text from outside (a sensor's metadata, a device name, a file path) made fit for a free-text
// field of SensorInfo: control characters and bytes of no UTF-8 character become '?' and it is cut to `max_bytes` (kMaxName or
// kMaxSource) without splitting a UTF-8 character. A driver copies outside text through this, so
// an odd byte from a sensor never makes the description invalid (which would stop the driver).
std::string sensor_text(std::string_view text, std::size_t max_bytes);

// "1920x1200 plumb_bob fx=1000.0 fy=1000.0 cx=960.0 cy=600.0", for tools' one-line summaries.
std::string summary(const CameraCalibration& calibration);

}  // namespace sim
