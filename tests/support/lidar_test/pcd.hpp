// SPDX-License-Identifier: Apache-2.0
// Test-only: one reader of PCD files (v0.7) for every test that reads one: nebula's reference
// clouds (x y z, or x y z and more fields of other types) and the files sim_dump writes through
// PCL (binary or ascii). Every field is read as a float, whatever its stored type.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace lidar_test {

struct Xyz {
  float x, y, z;
};

struct PointCloudFile {
  std::string fields;           // the FIELDS line's names, "x y z intensity"
  std::string data;             // "binary" or "ascii"
  std::size_t points = 0;
  std::vector<float> values;    // points × fields, point by point, in the file's order

  std::size_t field_count() const { return points == 0 ? 0 : values.size() / points; }
  float value(std::size_t point, std::size_t field) const { return values[point * field_count() + field]; }
  // The first three fields as points; throws std::runtime_error when they are not x y z.
  std::vector<Xyz> xyz() const;
};

// Throws std::runtime_error with one sentence when the file cannot be opened, its header is not
// one this reader knows (SIZE/TYPE/COUNT per field, DATA binary or ascii) or its data is cut short.
PointCloudFile read_pcd(const std::filesystem::path& path);

// The x y z of a PCD file whose first three fields are x y z (nebula's reference clouds).
inline std::vector<Xyz> read_xyz_pcd(const std::filesystem::path& path) { return read_pcd(path).xyz(); }

}  // namespace lidar_test
