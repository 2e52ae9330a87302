// SPDX-License-Identifier: Apache-2.0
// Per-laser corrections, from the YAML format of ros-drivers/velodyne (which nebula ships too:
// the nominal tables for the Pucks, VLP-32C, HDL-32E and VLS-128) or from an HDL-64E's own
// db.xml (degrees and centimetres, as Velodyne delivers it with each unit; read as the ROS
// driver's gen_calibration.py converts it).
//
// YAML: top-level `num_lasers`, `distance_resolution` and `lasers:`, a sequence of mappings
// (flow `- {key: value, …}` or block style) with laser_id, rot_correction, vert_correction
// (radians), dist_correction, dist_correction_x/_y, vert_offset_correction,
// horiz_offset_correction, focal_distance (metres), focal_slope, min_intensity, max_intensity.
// Only this subset of YAML is read; anything else is an error naming its line.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "sim/result.hpp"

namespace sim::velodyne {

struct LaserCorrection {
  double rot_correction = 0;           // radians, subtracted from the azimuth
  double vert_correction = 0;          // radians, the laser's elevation
  double dist_correction = 0;          // metres, added to every non-zero distance
  double dist_correction_x = 0;        // metres: HDL-64E two-point correction
  double dist_correction_y = 0;
  double vert_offset_correction = 0;   // metres: optical centre above the origin
  double horiz_offset_correction = 0;  // metres: optical centre beside the axis
  double focal_distance = 0;           // HDL-64E intensity model
  double focal_slope = 0;
  double min_intensity = 0;
  double max_intensity = 255;

  // ros-drivers' rule: the two-point correction applies when both X and Y values are given.
  bool two_point() const noexcept { return dist_correction_x != 0 && dist_correction_y != 0; }
  // Whether the point needs the full HDL-64E model (offsets, two-point) or only polar geometry.
  bool needs_full_model() const noexcept {
    return two_point() || vert_offset_correction != 0 || horiz_offset_correction != 0;
  }
  bool corrects_intensity() const noexcept {
    return focal_slope != 0 || min_intensity != 0 || max_intensity != 255;
  }
};

class Calibration {
 public:
  // Parses the YAML text. `source` names the file in messages ("VLP16.yaml:12: …").
  static Expected<Calibration> parse_yaml(std::string_view text, std::string_view source = "calibration");
  // Parses an HDL-64E db.xml (boost serialization: DB/distLSB_, enabled_, minIntensity_,
  // maxIntensity_, points_/item/px/{id_, rotCorrection_, …}). Disabled lasers keep their place
  // with zero corrections, so laser numbers stay those of the packets.
  static Expected<Calibration> parse_db_xml(std::string_view text, std::string_view source = "db.xml");
  // Reads a file: db.xml when it starts with '<' (after blanks), YAML otherwise.
  static Expected<Calibration> load(const std::filesystem::path& path);
  // From values already in memory (tests).
  static Expected<Calibration> from_lasers(std::vector<LaserCorrection> lasers);

  std::size_t lasers() const noexcept { return lasers_.size(); }
  const LaserCorrection& operator[](std::size_t laser) const noexcept { return lasers_[laser]; }
  // Ring of each laser as ros-drivers/velodyne numbers it: lasers ordered by elevation, the
  // lowest is ring 0 (what LIO-SAM and other deskewing pipelines expect).
  std::uint16_t ring(std::size_t laser) const noexcept { return rings_[laser]; }
  // The file's distance_resolution (metres; nullopt when absent). The decoder uses the model's
  // own unit: the VLS-128's nominal file says 0.007 where the sensor sends 4 mm.
  double file_distance_resolution_m() const noexcept { return file_resolution_m_; }

 private:
  explicit Calibration(std::vector<LaserCorrection> lasers, double resolution_m);
  std::vector<LaserCorrection> lasers_;
  std::vector<std::uint16_t> rings_;
  double file_resolution_m_ = 0;
};

}  // namespace sim::velodyne
