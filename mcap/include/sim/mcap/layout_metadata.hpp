// SPDX-License-Identifier: Apache-2.0
// A SIM stream's layout and capacity kept in an MCAP channel's metadata ("sim.*" keys), so
// sim_play recreates the stream exactly as it was recorded (same capacity, same max_points, same
// stride), plus the ROS 2 profile's required "offered_qos_profiles".
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sim/layout.hpp"
#include "sim/mcap/format.hpp"

namespace sim::mcap {

struct StreamShape {
  Layout layout{};
  std::uint64_t capacity = 0;  // bytes per slot
};

// sim.stream, sim.layout (human readable), sim.kind, sim.capacity and the layout's fields, and
// offered_qos_profiles (ROS 2 "sensor data": keep last 5, best effort, volatile).
Metadata stream_metadata(const std::string& stream, const Layout& layout, std::uint64_t capacity);

// The shape recorded by stream_metadata(); nullopt when the channel was not recorded by SIM or
// its sim.* keys do not describe a valid layout.
std::optional<StreamShape> stream_shape(const Metadata& metadata);

// The ROS 2 sensor-data QoS profile as rosbag2 stores it (a YAML list with one profile).
const std::string& sensor_data_qos_yaml();

}  // namespace sim::mcap
