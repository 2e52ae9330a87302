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
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "packet_builder.hpp"
#include "hesai_test_data.hpp"
#include "lidar_test/golden.hpp"
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

// A row of the table: its name and how to make its packets, calibration and options (read
// when the case runs, not when the table is made).
struct GoldenCase {
  std::string name;
  std::function<Scenario()> make;
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

Scenario p64(std::string name) {
  return capture(std::move(name), "pandar64_dual.pcap", "pandar64.calibration.csv", Model::pandar64);
}
Scenario xt32(std::string name) {
  return capture(std::move(name), "pandarxt32_dual.pcap", "pandarxt32.calibration.csv", Model::pandar_xt32);
}
Scenario qt128(std::string name) {
  return capture(std::move(name), "pandarqt128_dual.pcap", "pandarqt128.calibration.csv", Model::pandar_qt128);
}

// Every case, in the order of golden_frames.txt.
std::vector<GoldenCase> golden_cases() {
  std::vector<GoldenCase> out;
  auto add = [&out](std::string name, std::function<Scenario(std::string)> make) {
    out.push_back({name, [name, make] { return make(name); }});
  };
  add("pandar64", p64);
  add("pandar64_block_cut", [](std::string name) {
    Scenario s = p64(std::move(name));
    s.options.cut_by = CutBy::block_azimuth;
    return s;
  });
  add("pandar64_cut180_partial_flush", [](std::string name) {
    Scenario s = p64(std::move(name));
    s.options.cut_azimuth_deg = 180.0;
    s.options.emit_partial_frames = true;
    s.flush = true;
    return s;
  });
  add("pandar64_filters", [](std::string name) {
    Scenario s = p64(std::move(name));
    s.options.min_range_m = 1.5f;
    s.options.max_range_m = 60.0f;
    s.options.drop_identical_returns = false;
    s.options.multi_return_distance_threshold_m = 0.5f;
    s.options.drop_zero_distance = false;
    return s;
  });
  add("pandar64_firetime_compensation", [](std::string name) {
    Scenario s = p64(std::move(name));
    auto f = FiretimeCorrection::load(data_path("pandar64.example-firetimes.csv"), Model::pandar64);
    if (!f) throw std::runtime_error(f.error().message);
    s.options.firetimes = *f;
    s.options.firetime_azimuth_compensation = true;
    return s;
  });
  add("pandar64_small_span", [](std::string name) {
    Scenario s = p64(std::move(name));
    s.span_fraction = 0.3;  // about 80 % of a revolution's points
    return s;
  });
  add("pandar64_late_span", [](std::string name) {
    Scenario s = p64(std::move(name));
    s.late_by_packets = 200;  // more than the carry-over holds
    return s;
  });

  add("xt32", xt32);
  add("xt32_block_cut", [](std::string name) {
    Scenario s = xt32(std::move(name));
    s.options.cut_by = CutBy::block_azimuth;
    return s;
  });

  add("qt128", qt128);
  add("qt128_cut90_filters_flush", [](std::string name) {
    Scenario s = qt128(std::move(name));
    s.options.cut_azimuth_deg = 90.0;
    s.options.min_range_m = 0.5f;
    s.options.max_range_m = 20.0f;
    s.options.multi_return_distance_threshold_m = 0.0f;
    s.flush = true;
    return s;
  });
  add("qt128_late_span_flush", [](std::string name) {
    Scenario s = qt128(std::move(name));
    s.late_by_packets = 200;
    s.flush = true;
    return s;
  });

  add("pandar40p_partial_flush", [](std::string name) {
    Scenario s = capture(std::move(name), "pandar40p_last_20hz_raw.pcapng", "pandar40p.example-calibration.csv",
                         Model::pandar40p);
    s.options.emit_partial_frames = true;
    s.flush = true;
    return s;
  });

  add("xt16_single", [](std::string name) { return synthetic(std::move(name), Model::pandar_xt16, 1); });
  add("xt16_dual", [](std::string name) { return synthetic(std::move(name), Model::pandar_xt16, 2); });
  add("xt32m_triple", [](std::string name) { return synthetic(std::move(name), Model::pandar_xt32m, 3); });
  add("xt32m_triple_no_duplicate_filters", [](std::string name) {
    Scenario s = synthetic(std::move(name), Model::pandar_xt32m, 3);
    s.options.drop_identical_returns = false;
    s.options.multi_return_distance_threshold_m = 0.0f;
    s.options.drop_zero_distance = false;
    return s;
  });
  add("qt64_dual", [](std::string name) { return synthetic(std::move(name), Model::pandar_qt64, 2); });
  add("qt128_single", [](std::string name) { return synthetic(std::move(name), Model::pandar_qt128, 1); });
  add("qt128_dual", [](std::string name) { return synthetic(std::move(name), Model::pandar_qt128, 2, 0); });
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

// The recorded lines: every line of golden_frames.txt that is not a comment.
std::vector<std::string> recorded_lines() {
  std::vector<std::string> lines;
  std::istringstream text(hesai_test::read_text(data_path("golden_frames.txt")));
  for (std::string line; std::getline(text, line);) {
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  return lines;
}

std::string case_of(const std::string& line) { return line.substr(0, line.find(' ')); }

class HesaiGolden : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(HesaiGolden, EveryFrameIsByteIdenticalToTheRecordedDecoder) {
#if !defined(__x86_64__)
  GTEST_SKIP() << "the digests were recorded on x86-64 (IEEE single precision, no fma)";
#endif
  const GoldenCase& c = GetParam();
  const std::vector<std::string> lines = run(c.make());
  // Every case must produce frames, or the pin would hold for a decoder that drops all.
  EXPECT_GE(lines.size() - 1, 1u) << "no frame";

  std::vector<std::string> expected;
  for (const auto& line : recorded_lines()) {
    if (case_of(line) == c.name) expected.push_back(line);
  }
  ASSERT_EQ(lines.size(), expected.size()) << "a different number of frames than recorded";
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // The first difference says which frame moved; the rest follow from it.
    ASSERT_EQ(lines[i], expected[i]) << "line " << i << " of " << c.name << " in golden_frames.txt";
  }
}

INSTANTIATE_TEST_SUITE_P(Recorded, HesaiGolden, ::testing::ValuesIn(golden_cases()), lidar_test::CaseName{});

// The file pins the table and nothing else: no case is left out, none is only in the file.
TEST(HesaiGoldenFile, HoldsTheTablesCasesInTheTablesOrder) {
  std::vector<std::string> in_file;
  for (const auto& line : recorded_lines()) {
    if (in_file.empty() || in_file.back() != case_of(line)) in_file.push_back(case_of(line));
  }
  std::vector<std::string> in_table;
  for (const GoldenCase& c : golden_cases()) in_table.push_back(c.name);
  EXPECT_EQ(in_file, in_table);
}

// Re-recording is a step before the tests, not a test: with SIM_HESAI_WRITE_GOLDEN set, the file
// is written before any test runs, and the tests then compare against what was just written.
class RecordWhenAsked : public ::testing::Environment {
 public:
  void SetUp() override {
    const char* out = std::getenv("SIM_HESAI_WRITE_GOLDEN");
    if (out == nullptr) return;
    std::ofstream file(out);
    file << "# FrameAssembler output digests (FNV-1a 64 of each frame's metadata and point bytes),\n"
            "# written by test_hesai_golden with SIM_HESAI_WRITE_GOLDEN; see that test.\n";
    for (const GoldenCase& c : golden_cases()) {
      for (const auto& l : run(c.make())) file << l << '\n';
    }
    ASSERT_TRUE(file.good()) << "cannot write " << out;
  }
};
[[maybe_unused]] ::testing::Environment* const record_when_asked =
    ::testing::AddGlobalTestEnvironment(new RecordWhenAsked);

}  // namespace
