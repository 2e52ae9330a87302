// SPDX-License-Identifier: Apache-2.0
// Writes the fuzz seed corpus (corpus/) from the test encoder: valid L2 and L1 streams, with the
// fuzzer's one-byte prefix (model bit, scan size, chunk size). Run by hand when the encoder
// changes: make_unitree_corpus <dir>.
#include <cstdio>
#include <fstream>
#include <string>

#include "unitree_encoder.hpp"

using namespace unitree_test;

namespace {
void write(const std::string& dir, const std::string& name, std::uint8_t prefix, const Bytes& b) {
  std::ofstream out(dir + "/" + name, std::ios::binary);
  out.put(static_cast<char>(prefix));
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_unitree_corpus DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  L2PointSpec p;
  p.range_scale = 0.001F;
  p.angle_increment = 0.01F;
  p.com_horizontal_angle_step = 0.001F;
  p.time_increment = 1e-5F;
  for (std::size_t j = 0; j < 300; ++j) {
    p.ranges[j] = static_cast<std::uint16_t>(500 + 7 * j);
    p.intensities[j] = static_cast<std::uint8_t>(j);
  }
  L2ImuSpec imu;
  imu.angular_velocity = {0.1F, 0.2F, 0.3F};
  Bytes l2 = concat({l2_point_packet(p), l2_imu_packet(imu)});
  p.seq = 1;
  l2 = concat({l2, l2_point_packet(p), robosense_packet(), l2_packet(103, Bytes(5512))});
  write(dir, "l2_stream_chunk1", 0x00, l2);
  write(dir, "l2_stream_chunk1400", static_cast<std::uint8_t>(15 << 3), l2);
  write(dir, "l2_imu_only", 0x02, l2_imu_packet(imu));

  std::array<std::uint16_t, 120> ranges{};
  for (std::size_t j = 0; j < 90; ++j) ranges[j] = static_cast<std::uint16_t>(1000 + j);
  L1AuxSpec aux;
  aux.packet_id = 4;
  aux.sys_vertical_angle_span = 0.75F;
  aux.com_horizontal_angle_step = 3.0F;
  aux.b_axis_dist = 15.0F;
  const Bytes l1 = concat({l1_distance_frame(4, ranges, 0), l1_auxiliary_frame(aux, 1),
                           l1_imu_frame({0, 0, 0, 1}, {0.1F, 0, 0}, {0, 0, 9.8F}, 4, 2)});
  write(dir, "l1_stream_chunk1", 0x01, l1);
  write(dir, "l1_stream_chunk98", 0x09, l1);
  std::printf("wrote seeds to %s\n", dir.c_str());
  return 0;
}
