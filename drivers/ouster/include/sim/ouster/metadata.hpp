// SPDX-License-Identifier: Apache-2.0
// An Ouster sensor's metadata: what its HTTP API returns for GET /api/v1/sensor/metadata and
// what users keep as a JSON file beside their recordings. Firmware 2.x writes flat keys
// (beam_altitude_angles, data_format, lidar_to_sensor_transform, prod_line, …); firmware 3.x
// nests them (beam_intrinsics, lidar_intrinsics, imu_intrinsics, lidar_data_format,
// config_params, sensor_info). Both are read into one checked structure.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "sim/ouster/packet.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

struct Metadata {
  // The sensor.
  std::string prod_line;    // "OS-1-32-G"
  std::string serial;       // prod_sn
  std::string firmware;     // build_rev, "v2.1.1"
  std::string lidar_mode;   // "1024x10"
  std::string timestamp_mode;  // config_params: "TIME_FROM_PTP_1588", …; empty when not given
  std::uint32_t init_id = 0;  // initialization_id; 0 when the metadata has none
  // The packets.
  PacketFormat format;
  std::array<unsigned, 2> column_window{0, 0};  // first and last column the sensor sends
  std::vector<int> pixel_shift_by_row;          // H entries: destaggering
  std::uint16_t udp_port_lidar = 7502;
  std::uint16_t udp_port_imu = 7503;
  // The geometry: per beam (H entries), degrees.
  std::vector<double> beam_altitude_deg;
  std::vector<double> beam_azimuth_deg;
  // 4×4 row-major; translations in millimetres.
  std::array<double, 16> beam_to_lidar{};   // FW 3.x; from lidar_origin_to_beam_origin_mm on 2.x
  std::array<double, 16> lidar_to_sensor{};
  std::array<double, 16> imu_to_sensor{};
  double lidar_origin_to_beam_origin_mm = 0;
  // Frames per second from the lidar mode ("1024x10": 10).
  unsigned frequency_hz = 10;

  // Parses the JSON text; every failure is one sentence naming the key and what to do.
  static Expected<Metadata> parse(std::string_view json);
  // Reads and parses a file; messages name the file.
  static Expected<Metadata> load(const std::filesystem::path& path);

  unsigned beams() const noexcept { return format.pixels_per_column; }
  unsigned columns() const noexcept { return format.columns_per_frame; }
  // Columns in one frame's window (column_window may cover part of the circle).
  unsigned window_columns() const noexcept;
  // "OS-1-32-G (sn 992101000280, v2.1.1), LEGACY, 32 beams × 1024 columns at 10 Hz".
  std::string describe() const;
};

}  // namespace sim::ouster
