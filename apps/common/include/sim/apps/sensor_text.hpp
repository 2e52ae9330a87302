// SPDX-License-Identifier: Apache-2.0
// A stream's sensor description for people and scripts, the same in every tool (sim_ls,
// sim_echo, sim_dump):
//   frame camera_front_optical in base_link at x 1.5 y 0 z 1.2 m, rpy -1.571 0 -1.571 rad;
//   calibration 768x576 plumb_bob fx=612.4 … from file:///etc/cam.yaml; Allied Vision 1800 U-240c
//   serial 0815; time sensor_synchronized (PTP Slave)
// and as one JSON object (matrices row-major, the rotation as the quaternion x, y, z, w).
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "sim/sensor_info.hpp"

namespace sim::apps {

// One line (no newline) for a person.
std::string describe_sensor(const SensorInfo& info);

// One JSON object: frame_id, parent_frame, mounting ({translation, rotation, rpy} or null),
// calibration (every CameraInfo field and its summary, or null), identity, calibration_source,
// time_base, time_sync, point_time.
std::string sensor_json(const SensorInfo& info);

// `text` as a JSON string, quotes included.
std::string json_string(std::string_view text);

// Appends "name":value to a JSON object being built ("{" so far, or "{…" with fields).
void json_field(std::string& object, const char* name, const std::string& value);

// The mounting's rotation as roll, pitch, yaw (radians; the inverse of Mounting::from_xyz_rpy).
std::array<double, 3> roll_pitch_yaw(const Mounting& mounting) noexcept;

}  // namespace sim::apps
