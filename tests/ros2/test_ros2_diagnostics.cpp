// SPDX-License-Identifier: Apache-2.0
// diagnostic_msgs/msg/DiagnosticArray, the message a stream's clock leaves the host in: the type
// hash ROS 2 Jazzy generated, exact XCDR1 bytes, round trips, one sentence for bad input, and the
// clock record as a status (levels, messages) and back.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/type_hash.hpp"

namespace {

using namespace sim;
using namespace sim::ros2;

// A PTP clock with every field set to something other than its default.
ClockStatus ptp_clock() {
  ClockStatus c;
  c.source = ClockSource::ptp;
  c.state = ClockState::locked;
  c.ptp_domain = 0;
  c.offset_from_master_ns = -42;
  c.path_delay_ns = 1'500;
  c.grandmaster = "00a069.fffe.0b552d";
  c.utc_offset_s = 37;
  c.ptp_timescale = true;
  c.tai_correction_ns = 37'000'000'000;
  c.reported_ns = 1'790'000'000'123'456'789;
  c.offset_to_host_ns = 12'345;
  c.spread_ns = 3'000;
  c.drift_ppm = 0.1 + 0.2;  // not a short decimal: the text must still read back exactly
  c.steps = 2;
  c.last_step_ns = -37'000'000'000;
  c.packets_measured = 123'456;
  c.measured_ns = 1'790'000'000'987'654'321;
  c.verdict = ClockVerdict::ok;
  c.stamps = StampClock::sensor_tai_corrected;
  return c;
}

std::uint32_t u32_at(const std::vector<std::byte>& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// Checked against a ROS 2 Jazzy install: share/diagnostic_msgs/msg/DiagnosticArray.json
// ("type_hashes") and diagnostic_array__description.c carry these (docs/ros2-interop.md).
TEST(Ros2Diagnostics, TypeHashesEqualTheOnesRos2JazzyGenerated) {
  EXPECT_EQ(rihs01_type_hash("diagnostic_msgs/msg/DiagnosticArray"),
            "RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e");
  EXPECT_EQ(rihs01_type_hash("diagnostic_msgs/msg/DiagnosticStatus"),
            "RIHS01_b0e3e692ea2d54a8af2f4ef1930e81556a2db55216b771f8a7d2724ed47bf0e4");
  EXPECT_EQ(rihs01_type_hash("diagnostic_msgs/msg/KeyValue"),
            "RIHS01_d68081eaa540288c5440753baecef0c4e16e81a5f78ad68902ded5100413bb42");
  EXPECT_EQ(rihs01_type_hash(diagnostic_array_type_name), rihs01_type_hash("diagnostic_msgs/msg/DiagnosticArray"));
}

TEST(Ros2Diagnostics, BytesFollowXcdr1) {
  DiagnosticArray a;
  a.stamp = Time{7, 9};
  a.status.push_back({DiagnosticLevel::warn, "n", "m", "hw", {{"k", "v"}}});
  const auto bytes = encode_diagnostic_array(a).value();
  // origin offsets: 0 sec, 4 nanosec, 8 frame_id len 1, 12 "\0", 16 status count, 20 level,
  // 24 name len 2, 28 "n\0", 32 message len, 36 "m\0", 40 hardware_id len 3, 44 "hw\0",
  // 48 values count, 52 key len, 56 "k\0", 60 value len, 64 "v\0"
  EXPECT_EQ(u32_at(bytes, 4 + 8), 1u);
  EXPECT_EQ(u32_at(bytes, 4 + 16), 1u);
  EXPECT_EQ(bytes[4 + 20], std::byte{1});
  EXPECT_EQ(u32_at(bytes, 4 + 24), 2u);
  EXPECT_EQ(u32_at(bytes, 4 + 40), 3u);
  EXPECT_EQ(u32_at(bytes, 4 + 48), 1u);
  EXPECT_EQ(u32_at(bytes, 4 + 60), 2u);
  EXPECT_EQ(bytes.size(), 4u + 66);
}

TEST(Ros2Diagnostics, RoundTripsEveryStatus) {
  DiagnosticArray a;
  a.stamp = Time{1'790'000'000, 5};
  a.status.push_back({DiagnosticLevel::ok, "sim: /a clock", "fine", "SN1", {{"x", "1"}, {"y", ""}}});
  a.status.push_back({DiagnosticLevel::stale, "sim: /b clock", "", "", {}});
  auto back = decode_diagnostic_array(encode_diagnostic_array(a).value());
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->stamp, a.stamp);
  EXPECT_EQ(back->status, a.status);
}

TEST(Ros2Diagnostics, EveryTruncationIsDroppedWithASentence) {
  DiagnosticArray a;
  a.status.push_back(clock_diagnostic("/lidar", "SN1", ptp_clock(), true));
  const auto bytes = encode_diagnostic_array(a).value();
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    auto r = decode_diagnostic_array(std::span(bytes).first(n));
    ASSERT_FALSE(r.has_value()) << n;
    EXPECT_NE(r.error().message.find("dropped a malformed diagnostic_msgs/msg/DiagnosticArray"),
              std::string::npos);
  }
}

TEST(Ros2Diagnostics, AHugeDeclaredCountIsRefusedBeforeAnythingIsAllocated) {
  DiagnosticArray a;
  auto bytes = encode_diagnostic_array(a).value();
  const std::uint32_t huge = 0xfffffff0u;
  std::memcpy(bytes.data() + 4 + 16, &huge, 4);
  auto r = decode_diagnostic_array(bytes);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("statuses, more than it holds"), std::string::npos);
}

TEST(Ros2Diagnostics, ATextWithANulIsNotSent) {
  DiagnosticArray a;
  a.status.push_back({DiagnosticLevel::ok, std::string("a\0b", 3), "", "", {}});
  auto r = encode_diagnostic_array(a);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("NUL"), std::string::npos);
}

TEST(Ros2ClockDiagnostic, AnOkClockIsOkWithItsSummaryAndEveryValue) {
  const ClockStatus c = ptp_clock();
  const DiagnosticStatus s = clock_diagnostic("/lidar_top", "SN42", c, true);
  EXPECT_EQ(s.level, DiagnosticLevel::ok);
  EXPECT_EQ(s.name, "sim: /lidar_top clock");
  EXPECT_EQ(s.hardware_id, "SN42");
  EXPECT_EQ(s.message, summary(c));
  for (const char* key : {"clock_source", "sync_state", "offset_from_master_ns", "grandmaster_id",
                          "offset_to_host_ns", "spread_ns", "drift_ppm", "steps",
                          "tai_correction_ns", "stamps"}) {
    EXPECT_NE(s.value(key), nullptr) << key;
  }
  EXPECT_EQ(*s.value("clock_source"), "ptp");
  EXPECT_EQ(*s.value("sync_state"), "locked");
  EXPECT_EQ(*s.value("offset_from_master_ns"), "-42");
  EXPECT_EQ(*s.value("grandmaster_id"), "00a069.fffe.0b552d");
  EXPECT_EQ(*s.value("offset_to_host_ns"), "12345");
  EXPECT_EQ(*s.value("tai_correction_ns"), "37000000000");
  EXPECT_EQ(*s.value("stamps"), "sensor_tai_corrected");
}

TEST(Ros2ClockDiagnostic, LevelsFollowTheVerdictAndTheProblemIsTheMessage) {
  ClockStatus c = ptp_clock();
  c.verdict = ClockVerdict::warn;
  c.problem = "the clock stepped; check ptp4l";
  DiagnosticStatus s = clock_diagnostic("/l", "/l", c, true);
  EXPECT_EQ(s.level, DiagnosticLevel::warn);
  EXPECT_EQ(s.message, c.problem);
  c.verdict = ClockVerdict::error;
  c.problem = "stamps are 37 s ahead of the host; fix the PTP timescale";
  s = clock_diagnostic("/l", "/l", c, true);
  EXPECT_EQ(s.level, DiagnosticLevel::error);
  EXPECT_EQ(s.message, c.problem);
  c.verdict = ClockVerdict::unknown;
  c.problem.clear();
  s = clock_diagnostic("/l", "/l", c, true);
  EXPECT_EQ(s.level, DiagnosticLevel::ok);
  EXPECT_EQ(s.message.rfind("clock not measured yet: ", 0), 0u) << s.message;
}

TEST(Ros2ClockDiagnostic, AStoppedWriterIsStaleAndAStreamWithoutAClockSaysSo) {
  DiagnosticStatus s = clock_diagnostic("/l", "/l", ptp_clock(), false);
  EXPECT_EQ(s.level, DiagnosticLevel::stale);
  EXPECT_EQ(s.message.rfind("the writer stopped; last clock: ", 0), 0u) << s.message;
  EXPECT_NE(s.value("clock_source"), nullptr);
  s = clock_diagnostic("/l", "/l", std::nullopt, true);
  EXPECT_EQ(s.level, DiagnosticLevel::stale);
  EXPECT_EQ(s.message, "the writer of /l reports no clock");
  EXPECT_TRUE(s.values.empty());
  EXPECT_FALSE(clock_from_diagnostic(s).has_value());
}

TEST(Ros2ClockDiagnostic, TheRecordReadsBackFieldByField) {
  for (ClockStatus c : {ptp_clock(), ClockStatus{}}) {
    c.problem = c.source == ClockSource::ptp ? "a sentence, with: punctuation" : "";
    auto wire = encode_diagnostic_array({Time{1, 0}, "", {clock_diagnostic("/x", "/x", c, true)}});
    auto array = decode_diagnostic_array(wire.value());
    ASSERT_TRUE(array.has_value()) << array.error().message;
    auto back = clock_from_diagnostic(array->status.at(0));
    ASSERT_TRUE(back.has_value()) << back.error().message;
    EXPECT_TRUE(*back == c) << summary(*back) << " vs " << summary(c);
    EXPECT_EQ(back->drift_ppm, c.drift_ppm);
  }
}

TEST(Ros2ClockDiagnostic, AValueThatIsNotANumberIsNamed) {
  DiagnosticStatus s = clock_diagnostic("/x", "/x", ptp_clock(), true);
  for (KeyValue& kv : s.values) {
    if (kv.key == "spread_ns") kv.value = "12 µs";
  }
  auto back = clock_from_diagnostic(s);
  ASSERT_FALSE(back.has_value());
  EXPECT_NE(back.error().message.find("spread_ns"), std::string::npos) << back.error().message;
}

TEST(Ros2ClockDiagnostic, TheStreamComesBackFromTheName) {
  EXPECT_EQ(stream_of_clock_diagnostic(clock_diagnostic_name("/cam/front")), "/cam/front");
  EXPECT_FALSE(stream_of_clock_diagnostic("velodyne: Timestamp Status").has_value());
  EXPECT_FALSE(stream_of_clock_diagnostic("sim:  clock").has_value());
  SensorInfo info;
  EXPECT_EQ(clock_hardware_id("/l", info), "/l");
  info.identity.serial = "122233000123";
  EXPECT_EQ(clock_hardware_id("/l", info), "122233000123");
}

}  // namespace
