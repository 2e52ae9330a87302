// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the decoders behind the checksums. Random bytes almost never pass a
// CRC, so fuzz_unitree_stream rarely reaches the point math; here the input becomes the body of
// a packet and its checksum is made valid, so every header field (calibration floats, point
// counts, angles, stamps) takes arbitrary values. The first byte (mod 4) picks L2 3D point,
// L2 IMU, an L1 distance+auxiliary pair (with trimmed payloads), or an L2 2D-mode packet.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "sim/unitree/crc.hpp"
#include "sim/unitree/decoder.hpp"

namespace {

class CheckingSink : public sim::unitree::ScanSink {
 public:
  explicit CheckingSink(std::size_t capacity) : storage_(capacity) {}
  std::span<sim::LidarPoint> begin_scan() override { return storage_; }
  void end_scan(std::size_t points, std::int64_t, std::int64_t) override {
    if (points > storage_.size()) std::abort();
    for (std::size_t i = 0; i < points; ++i) {
      const auto& p = storage_[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
      if (p.ring != 0 || p.reserved != 0) std::abort();
    }
  }
  void imu(const sim::unitree::ImuSample&) override {}

 private:
  std::vector<sim::LidarPoint> storage_;
};

void put_u32(std::vector<std::uint8_t>& b, std::size_t off, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) b[off + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::vector<std::uint8_t> l2_packet(std::uint32_t type, std::size_t data_size,
                                 std::span<const std::uint8_t> body) {
  std::vector<std::uint8_t> p(12 + data_size + 12);
  p[0] = std::uint8_t{0x55};
  p[1] = std::uint8_t{0xAA};
  p[2] = std::uint8_t{0x05};
  p[3] = std::uint8_t{0x0A};
  put_u32(p, 4, type);
  put_u32(p, 8, static_cast<std::uint32_t>(p.size()));
  std::memcpy(p.data() + 12, body.data(), std::min(body.size(), data_size));
  put_u32(p, 12 + data_size,
          sim::unitree::crc32(std::span<const std::uint8_t>(p).subspan(12, data_size)));
  return p;
}

std::vector<std::uint8_t> mavlink(std::uint32_t msgid, std::uint8_t crc_extra, std::size_t full,
                               std::span<const std::uint8_t> body) {
  // A MAVLink v2 payload is at most 255 bytes (its length is one byte). Saying so also gives
  // GCC 12 the bound it needs: without it, -O3 warns the memcpy below may copy ~2^64 bytes.
  const std::size_t len = std::min({body.size(), full, std::size_t{255}});
  std::vector<std::uint8_t> f(10 + len + 2);
  f[0] = std::uint8_t{0xFD};
  f[1] = static_cast<std::uint8_t>(len);
  f[7] = static_cast<std::uint8_t>(msgid);
  std::memcpy(f.data() + 10, body.data(), len);
  sim::unitree::Crc16Mcrf4xx crc;
  crc.add(std::span<const std::uint8_t>(f).subspan(1, 9 + len));
  crc.add(crc_extra);
  f[10 + len] = static_cast<std::uint8_t>(crc.value() & 0xFF);
  f[11 + len] = static_cast<std::uint8_t>(crc.value() >> 8);
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::span<const std::uint8_t> body(data + 1, size - 1);
  sim::unitree::DecoderOptions options;
  options.packets_per_scan = 2;
  options.time_source = (data[0] & 4U) ? sim::unitree::TimeSource::sensor
                                       : sim::unitree::TimeSource::host;
  std::vector<std::uint8_t> stream;
  switch (data[0] % 4) {
    case 0: {
      const auto p = l2_packet(102, 1020, body);
      stream.insert(stream.end(), p.begin(), p.end());
      stream.insert(stream.end(), p.begin(), p.end());
      break;
    }
    case 1: {
      const auto p = l2_packet(104, 56, body);
      stream.insert(stream.end(), p.begin(), p.end());
      break;
    }
    case 3: {
      const auto p = l2_packet(103, 5512, body);  // 2D mode
      stream.insert(stream.end(), p.begin(), p.end());
      break;
    }
    default: {
      options.model = sim::unitree::Model::l1;
      const auto distance = mavlink(16, 74, 246, body);
      const auto aux = mavlink(17, 99, 209, body.size() > 246 ? body.subspan(246) : body);
      const auto imu = mavlink(19, 110, 42, body);
      for (int i = 0; i < 2; ++i) {
        stream.insert(stream.end(), distance.begin(), distance.end());
        stream.insert(stream.end(), aux.begin(), aux.end());
      }
      stream.insert(stream.end(), imu.begin(), imu.end());
      break;
    }
  }
  CheckingSink sink(sim::unitree::Decoder::max_points_per_scan(options));
  sim::unitree::Decoder decoder(options, sink);
  decoder.push(stream, 0);
  decoder.finish();
  return 0;
}
