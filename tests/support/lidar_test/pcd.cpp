// SPDX-License-Identifier: Apache-2.0
#include "lidar_test/pcd.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace lidar_test {
namespace {

struct Field {
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
};

std::vector<std::string> words_after_key(const std::string& line) {
  std::istringstream in(line);
  std::string word;
  in >> word;  // the key
  std::vector<std::string> words;
  while (in >> word) words.push_back(word);
  return words;
}

// One stored value as a float: F4/F8, U1/U2/U4/U8, I1/I2/I4/I8 (little-endian, as PCL writes).
float decode(const char* bytes, const Field& f, const std::filesystem::path& path) {
  auto as = [bytes](auto zero) {
    decltype(zero) v;
    std::memcpy(&v, bytes, sizeof v);
    return static_cast<float>(v);
  };
  switch (f.type) {
    case 'F':
      if (f.size == 4) return as(float{});
      if (f.size == 8) return as(double{});
      break;
    case 'U':
      if (f.size == 1) return as(std::uint8_t{});
      if (f.size == 2) return as(std::uint16_t{});
      if (f.size == 4) return as(std::uint32_t{});
      if (f.size == 8) return as(std::uint64_t{});
      break;
    case 'I':
      if (f.size == 1) return as(std::int8_t{});
      if (f.size == 2) return as(std::int16_t{});
      if (f.size == 4) return as(std::int32_t{});
      if (f.size == 8) return as(std::int64_t{});
      break;
    default:
      break;
  }
  throw std::runtime_error(path.string() + ": a field of type " + f.type + std::to_string(f.size) +
                           " is not one a PCD file stores");
}

}  // namespace

std::vector<Xyz> PointCloudFile::xyz() const {
  if (fields.rfind("x y z", 0) != 0) throw std::runtime_error("the PCD's first fields are not x y z: " + fields);
  std::vector<Xyz> out(points);
  for (std::size_t i = 0; i < points; ++i) out[i] = {value(i, 0), value(i, 1), value(i, 2)};
  return out;
}

PointCloudFile read_pcd(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  PointCloudFile pcd;
  std::vector<Field> fields;
  for (std::string line; std::getline(in, line);) {
    const auto words = words_after_key(line);
    if (line.rfind("FIELDS", 0) == 0) {
      pcd.fields = line.substr(7);
      fields.assign(words.size(), Field{});
    }
    for (std::size_t i = 0; i < words.size() && i < fields.size(); ++i) {
      if (line.rfind("SIZE", 0) == 0) fields[i].size = std::stoul(words[i]);
      if (line.rfind("TYPE", 0) == 0) fields[i].type = words[i].at(0);
      if (line.rfind("COUNT", 0) == 0) fields[i].count = std::stoul(words[i]);
    }
    if (line.rfind("POINTS ", 0) == 0) pcd.points = std::stoul(line.substr(7));
    if (line.rfind("DATA ", 0) == 0) {
      pcd.data = line.substr(5);
      break;
    }
  }
  if (fields.empty() || (pcd.data != "binary" && pcd.data != "ascii")) {
    throw std::runtime_error(path.string() + " is not a PCD file with FIELDS and DATA binary or ascii");
  }
  std::size_t per_point = 0;
  std::size_t stride = 0;
  for (const Field& f : fields) {
    per_point += f.count;
    stride += f.size * f.count;
  }
  pcd.values.resize(pcd.points * per_point);
  if (pcd.data == "ascii") {
    for (float& v : pcd.values) {
      if (!(in >> v)) throw std::runtime_error(path.string() + " holds fewer values than its POINTS say");
    }
    return pcd;
  }
  std::vector<char> bytes(stride * pcd.points);
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
    throw std::runtime_error(path.string() + " is cut short: fewer bytes than its POINTS say");
  }
  std::size_t at = 0;
  std::size_t out = 0;
  for (std::size_t p = 0; p < pcd.points; ++p) {
    for (const Field& f : fields) {
      for (std::size_t c = 0; c < f.count; ++c, at += f.size) pcd.values[out++] = decode(bytes.data() + at, f, path);
    }
  }
  return pcd;
}

}  // namespace lidar_test
