// SPDX-License-Identifier: Apache-2.0
// Byte-for-byte pin of what FrameAssembler publishes, so its hot path can be made faster
// without moving a single output bit. The reference tests compare points with nebula's clouds
// within 1 mm; these compare every byte of every frame (points and metadata) with digests
// recorded from the decoder before its per-group loop was rewritten for speed
// (data/golden_frames.txt, see below), for every bundled capture and for synthetic packets of
// the models without one, under option sets that take every branch of the decoder: both cut
// modes, another cut azimuth, partial frames and flush, every filter, firing-time
// compensation, a span too small, a span given late.
//
// The digests are of float bits: they hold where the arithmetic is plain IEEE single precision
// with no fused multiply-add, which is x86-64 without -march (what CI builds). Elsewhere (aarch64
// contracts a·b + c into one fma) the test skips; the 1 mm reference tests still run there.
//
// To re-record (only when an output change is intended, and say why in the commit):
//   SIM_HESAI_WRITE_GOLDEN=$PWD/tests/drivers/hesai/data/golden_frames.txt build/.../test_hesai_golden
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "packet_builder.hpp"
#include "pcap_payloads.hpp"
#include "sim/hesai/hesai.hpp"

using namespace sim::hesai;
using hesai_test::data_path;

namespace {

// FNV-1a, 64 bit: enough to tell two frames apart, and it needs no library.
class Digest {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ull;
    }
  }
  template <typename T>
  void value(T v) {
    bytes(&v, sizeof v);
  }
  std::uint64_t get() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

std::string hex(std::uint64_t v) {
  std::ostringstream s;
  s << std::hex << v;
  return s.str();
}

struct Scenario {
  std::string name;
  Model model;
  std::vector<std::vector<std::uint8_t>> packets;
  std::vector<std::int64_t> host_ns;
  Calibration calibration;
  AssemblerOptions options;
  double span_fraction = 1.0;   // of frame_capacity(model, 3)
  unsigned late_by_packets = 0;  // set_output this many packets after a frame completes
  bool flush = false;
};

Calibration load_calibration(const char* file, Model model) {
  auto c = Calibration::load(data_path(file), model);
  if (!c) throw std::runtime_error(c.error().message);
  return *c;
}

Scenario capture(std::string name, const char* pcap, const char* csv, Model model) {
  Scenario s{std::move(name), model, {}, {}, load_calibration(csv, model), {}, 1.0, 0, false};
  for (auto& p : hesai_test::read_udp_payloads(data_path(pcap))) {
    s.packets.push_back(std::move(p.bytes));
    s.host_ns.push_back(p.capture_ns);
  }
  s.options.model = model;
  return s;
}

// Two and a half turns of a model without a public capture. The distances visit every case
// the filters tell apart: no return, below the minimum range, identical returns (same
// distance and reflectivity), returns closer than the multi-return threshold, distinct ones.
Scenario synthetic(std::string name, Model model, unsigned returns, std::uint8_t mode_flag = 1) {
  const ModelInfo& m = info(model);
  std::vector<ChannelAngles> angles;
  for (unsigned ch = 0; ch < m.channels; ++ch) {
    angles.push_back({15.0f - 30.0f * static_cast<float>(ch) / static_cast<float>(m.channels),
                      0.37f * static_cast<float>(ch % 7) - 1.1f});
  }
  auto calibration = Calibration::from_angles(angles);
  if (!calibration) throw std::runtime_error(calibration.error().message);
  Scenario s{std::move(name), model, {}, {}, std::move(*calibration), {}, 1.0, 0, true};
  s.options.model = model;
  const unsigned groups = m.blocks_per_packet / returns;
  const unsigned step = m.azimuth_step_10hz;
  const unsigned packets = 5 * 36000 / (2 * step * groups);
  for (unsigned k = 0; k < packets; ++k) {
    hesai_test::SyntheticPacket p;
    p.channels = m.channels;
    p.blocks = m.blocks_per_packet;
    p.returns = returns;
    p.return_mode = returns == 3 ? 0x3d : returns == 2 ? 0x39 : 0x38;
    p.mode_flag = static_cast<std::uint8_t>(mode_flag ^ (k & 1));
    p.first_azimuth = static_cast<std::uint16_t>((k * groups * step + 9000) % 36000);
    p.azimuth_step = static_cast<std::uint16_t>(step);
    const auto us = static_cast<std::uint64_t>(k) * 100000 * groups * step / 36000;
    p.utc[5] = static_cast<std::uint8_t>(7 + us / 1000000);
    p.micros = static_cast<std::uint32_t>(us % 1000000);
    p.sequence = k;
    p.distance = [k, returns](unsigned block, unsigned ch) -> std::uint16_t {
      const unsigned r = block % returns;
      const unsigned base = ((ch * 7 + k) % 40 + 2) * 250;
      switch ((ch + k) % 6) {
        case 0: return 0;                                               // no return
        case 1: return static_cast<std::uint16_t>(r == 0 ? 5 : base);   // 2 cm: too close
        case 2: return static_cast<std::uint16_t>(base);                // identical returns
        case 3: return static_cast<std::uint16_t>(base + 10 * r);       // 4 cm apart
        default: return static_cast<std::uint16_t>(base + (50 + ch % 200) * r);
      }
    };
    p.reflectivity = [k](unsigned block, unsigned ch) {
      return static_cast<std::uint8_t>((ch + k) % 6 == 2 && ch % 2 ? block : ch + k);
    };
    s.packets.push_back(model == Model::pandar_qt64    ? hesai_test::build_qt64(p)
                        : model == Model::pandar_qt128 ? hesai_test::build_qt128(p)
                                                       : hesai_test::build_xt(p));
    s.host_ns.push_back(1'000'000'000 + static_cast<std::int64_t>(us) * 1000);
  }
  return s;
}

std::vector<Scenario> scenarios() {
  std::vector<Scenario> out;
  auto p64 = [&](std::string name) {
    return capture(std::move(name), "pandar64_dual.pcap", "pandar64.calibration.csv",
                   Model::pandar64);
  };
  out.push_back(p64("pandar64"));
  out.push_back(p64("pandar64_block_cut"));
  out.back().options.cut_by = CutBy::block_azimuth;
  out.push_back(p64("pandar64_cut180_partial_flush"));
  out.back().options.cut_azimuth_deg = 180.0;
  out.back().options.emit_partial_frames = true;
  out.back().flush = true;
  out.push_back(p64("pandar64_filters"));
  out.back().options.min_range_m = 1.5f;
  out.back().options.max_range_m = 60.0f;
  out.back().options.drop_identical_returns = false;
  out.back().options.multi_return_distance_threshold_m = 0.5f;
  out.back().options.drop_zero_distance = false;
  out.push_back(p64("pandar64_firetime_compensation"));
  {
    auto f = FiretimeCorrection::load(data_path("pandar64.example-firetimes.csv"), Model::pandar64);
    if (!f) throw std::runtime_error(f.error().message);
    out.back().options.firetimes = *f;
    out.back().options.firetime_azimuth_compensation = true;
  }
  out.push_back(p64("pandar64_small_span"));
  out.back().span_fraction = 0.3;  // about 80 % of a revolution's points
  out.push_back(p64("pandar64_late_span"));
  out.back().late_by_packets = 200;  // more than the carry-over holds

  auto xt32 = [&](std::string name) {
    return capture(std::move(name), "pandarxt32_dual.pcap", "pandarxt32.calibration.csv",
                   Model::pandar_xt32);
  };
  out.push_back(xt32("xt32"));
  out.push_back(xt32("xt32_block_cut"));
  out.back().options.cut_by = CutBy::block_azimuth;

  auto qt128 = [&](std::string name) {
    return capture(std::move(name), "pandarqt128_dual.pcap", "pandarqt128.calibration.csv",
                   Model::pandar_qt128);
  };
  out.push_back(qt128("qt128"));
  out.push_back(qt128("qt128_cut90_filters_flush"));
  out.back().options.cut_azimuth_deg = 90.0;
  out.back().options.min_range_m = 0.5f;
  out.back().options.max_range_m = 20.0f;
  out.back().options.multi_return_distance_threshold_m = 0.0f;
  out.back().flush = true;
  out.push_back(qt128("qt128_late_span_flush"));
  out.back().late_by_packets = 200;
  out.back().flush = true;

  out.push_back(capture("pandar40p_partial_flush", "pandar40p_last_20hz_raw.pcapng",
                        "pandar40p.example-calibration.csv", Model::pandar40p));
  out.back().options.emit_partial_frames = true;
  out.back().flush = true;

  out.push_back(synthetic("xt16_single", Model::pandar_xt16, 1));
  out.push_back(synthetic("xt16_dual", Model::pandar_xt16, 2));
  out.push_back(synthetic("xt32m_triple", Model::pandar_xt32m, 3));
  out.push_back(synthetic("xt32m_triple_no_duplicate_filters", Model::pandar_xt32m, 3));
  out.back().options.drop_identical_returns = false;
  out.back().options.multi_return_distance_threshold_m = 0.0f;
  out.back().options.drop_zero_distance = false;
  out.push_back(synthetic("qt64_dual", Model::pandar_qt64, 2));
  out.push_back(synthetic("qt128_single", Model::pandar_qt128, 1));
  out.push_back(synthetic("qt128_dual", Model::pandar_qt128, 2, 0));
  return out;
}

// One line per completed frame ("<scenario> <frame> <points> <digest>") and one with the
// assembler's counters at the end ("<scenario> counters - <digest>").
std::vector<std::string> run(const Scenario& s) {
  auto a = FrameAssembler::create(s.calibration, s.options);
  if (!a) throw std::runtime_error(a.error().message);
  const auto capacity = static_cast<std::size_t>(
      static_cast<double>(frame_capacity(s.model, 3)) * s.span_fraction);
  std::vector<std::string> lines;
  // A fresh span per frame, as a driver takes a new loan; points past point_count are not
  // part of the frame and are not compared.
  auto span = std::make_unique<std::vector<sim::LidarPoint>>(capacity);
  a->set_output(*span);
  unsigned give_in = 0;  // packets until the late span is given (0: none pending)
  auto record = [&](const CompletedFrame& f) {
    Digest d;
    d.value(f.point_count);
    d.value(f.stamp_ns);
    d.value(f.host_receive_ns);
    d.value(f.index);
    d.value(f.packets);
    d.value(f.lost_packets);
    d.value(f.dropped_points);
    d.value(f.whole);
    d.value(f.motor_rpm);
    d.value(f.safety.has_value());
    if (f.safety) {
      d.value(f.safety->state);
      d.value(f.safety->fault_type);
      d.value(f.safety->total_fault_codes);
      d.value(f.safety->fault_code_id);
      d.value(f.safety->fault_code);
      d.value(f.safety->rolling_counter);
    }
    d.bytes(span->data(), f.point_count * sizeof(sim::LidarPoint));
    lines.push_back(s.name + " " + std::to_string(f.index) + " " + std::to_string(f.point_count) +
                    " " + hex(d.get()));
    span = std::make_unique<std::vector<sim::LidarPoint>>(capacity);
    if (s.late_by_packets == 0) {
      a->set_output(*span);
    } else {
      give_in = s.late_by_packets;
    }
  };
  for (std::size_t i = 0; i < s.packets.size(); ++i) {
    if (give_in > 0 && --give_in == 0) a->set_output(*span);
    const PushResult r = a->push(s.packets[i], s.host_ns[i]);
    if (r.frame) record(*r.frame);
  }
  if (give_in > 0) a->set_output(*span);
  if (s.flush) {
    if (auto f = a->finish()) record(*f);
  }
  const AssemblerCounters& c = a->counters();
  Digest d;
  for (const std::uint64_t v : {c.packets, c.malformed, c.crc_errors, c.wrong_model,
                                c.lost_packets, c.out_of_order, c.frames, c.partial_frames_dropped,
                                c.frames_without_output, c.dropped_points}) {
    d.value(v);
  }
  for (const std::uint64_t v : c.rejected) d.value(v);
  lines.push_back(s.name + " counters - " + hex(d.get()));
  return lines;
}

}  // namespace

TEST(HesaiGolden, EveryFrameOfEveryCaptureIsByteIdenticalToTheRecordedDecoder) {
  std::vector<std::string> lines;
  std::map<std::string, std::size_t> frames_of;
  for (const Scenario& s : scenarios()) {
    const auto got = run(s);
    frames_of[s.name] = got.size() - 1;
    lines.insert(lines.end(), got.begin(), got.end());
  }
  if (const char* out = std::getenv("SIM_HESAI_WRITE_GOLDEN")) {
    std::ofstream file(out);
    file << "# FrameAssembler output digests (FNV-1a 64 of each frame's metadata and point bytes),\n"
            "# written by test_hesai_golden with SIM_HESAI_WRITE_GOLDEN; see that test.\n";
    for (const auto& l : lines) file << l << '\n';
    ASSERT_TRUE(file.good()) << "cannot write " << out;
    GTEST_SKIP() << "recorded " << lines.size() << " digests to " << out;
  }
#if !defined(__x86_64__)
  GTEST_SKIP() << "the digests were recorded on x86-64 (IEEE single precision, no fma)";
#endif
  // Every scenario must produce frames, or the pin would hold for a decoder that drops all.
  for (const auto& [name, frames] : frames_of) EXPECT_GE(frames, 1u) << name;

  std::vector<std::string> expected;
  std::istringstream text(hesai_test::read_text(data_path("golden_frames.txt")));
  for (std::string line; std::getline(text, line);) {
    if (!line.empty() && line[0] != '#') expected.push_back(line);
  }
  ASSERT_EQ(lines.size(), expected.size()) << "a different number of frames than recorded";
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // The first difference says which scenario and frame moved; the rest follow from it.
    ASSERT_EQ(lines[i], expected[i]) << "line " << i << " of golden_frames.txt";
  }
}
