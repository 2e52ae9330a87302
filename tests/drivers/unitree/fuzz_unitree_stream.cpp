// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the whole Unitree path on outside bytes: framing (L2 packets or L1
// MAVLink), CRC checks, point and IMU decoding and scan assembly. The first input byte picks the
// model (bit 0) and the chunk size the rest is pushed in (so packets split across reads are
// covered); the decoder must never write outside the storage it is lent nor emit non-finite
// points.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "sim/unitree/decoder.hpp"

namespace {

class CheckingSink : public sim::unitree::ScanSink {
 public:
  explicit CheckingSink(std::size_t capacity) : storage_(capacity + 1) {}
  std::span<sim::LidarPoint> begin_scan() override {
    // One guard point past the lent storage: it must never change.
    storage_.back() = guard();
    return std::span<sim::LidarPoint>(storage_).first(storage_.size() - 1);
  }
  void end_scan(std::size_t points, std::int64_t, std::int64_t) override {
    if (points > storage_.size() - 1) std::abort();
    const sim::LidarPoint g = guard();
    if (storage_.back().x != g.x || storage_.back().ring != g.ring) std::abort();
    for (std::size_t i = 0; i < points; ++i) {
      const auto& p = storage_[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
    }
  }
  void imu(const sim::unitree::ImuSample&) override {}

 private:
  static sim::LidarPoint guard() { return {1234.5F, 0, 0, 0, 0, 0xBEEF, 0, 0}; }
  std::vector<sim::LidarPoint> storage_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  sim::unitree::DecoderOptions options;
  options.model = (data[0] & 1U) ? sim::unitree::Model::l1 : sim::unitree::Model::l2;
  options.packets_per_scan = 1 + ((data[0] >> 1) & 3U);
  const std::size_t chunk = 1 + (std::size_t{data[0]} >> 3) * 97;
  CheckingSink sink(sim::unitree::Decoder::max_points_per_scan(options));
  sim::unitree::Decoder decoder(options, sink);
  std::span<const std::uint8_t> rest(data + 1, size - 1);
  while (!rest.empty()) {
    const std::size_t n = std::min(chunk, rest.size());
    decoder.push(rest.first(n), 0);
    rest = rest.subspan(n);
  }
  decoder.finish();
  return 0;
}
