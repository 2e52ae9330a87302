// SPDX-License-Identifier: Apache-2.0
// Issue 30 "Time you can trust", the bridge's part: a published stream's clock reaches another
// vendor's DDS node (Cyclone DDS, types from idlc) as ROS 2 diagnostics on /diagnostics, with the
// level of its verdict, its problem sentence, its sensor's serial and its values; a new clock
// record shows in the next array, and a writer that stopped turns its status STALE.
#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <string>

#include "bridge_test.hpp"
#include "cyclone.hpp"
#include "sim/clock_status.hpp"
#include "sim/ros2/diagnostics.hpp"
#include "sim/ros2/type_hash.hpp"
#include "sim/writer.hpp"

namespace {

using namespace bridge_test;
using Diagnostics = diagnostic_msgs_msg_dds__DiagnosticArray_;

// A clock in trouble: the sensor serves TAI, 37 s ahead of the host.
sim::ClockStatus tai_clock() {
  sim::ClockStatus c;
  c.source = sim::ClockSource::ptp;
  c.state = sim::ClockState::locked;
  c.ptp_domain = 0;
  c.offset_from_master_ns = -42;
  c.grandmaster = "00a069.fffe.0b552d";
  c.utc_offset_s = 37;
  c.ptp_timescale = true;
  c.offset_to_host_ns = 37'000'012'000;
  c.spread_ns = 3'000;
  c.drift_ppm = 0.25;
  c.steps = 1;
  c.verdict = sim::ClockVerdict::error;
  c.problem = "stamps are 37 s ahead of this host: the sensor serves TAI; start the driver with "
              "the TAI correction";
  c.stamps = sim::StampClock::sensor;
  return c;
}

// One stream's status as a Cyclone node received it.
struct Seen {
  int level = -1;
  std::string message;
  std::string hardware_id;
  std::map<std::string, std::string> values;
};

// Takes /diagnostics arrays until the status of `stream` satisfies `wanted`; nullopt when 60
// arrays came without it (a hang guard: the bridge sends one a second).
template <typename Wanted>
std::optional<Seen> wait_for_status(CycloneReader<Diagnostics>& reader, const std::string& stream,
                                    Wanted wanted) {
  const std::string name = sim::ros2::clock_diagnostic_name(stream);
  for (int i = 0; i < 60; ++i) {
    std::optional<Seen> found;
    const bool taken = reader.take([&](const Diagnostics& array) {
      for (std::uint32_t k = 0; k < array.status._length; ++k) {
        const auto& s = array.status._buffer[k];
        if (name != s.name) continue;
        Seen seen{s.level, s.message, s.hardware_id, {}};
        for (std::uint32_t v = 0; v < s.values._length; ++v) {
          seen.values[s.values._buffer[v].key] = s.values._buffer[v].value;
        }
        if (wanted(seen)) found = seen;
      }
    });
    if (!taken) return std::nullopt;
    if (found) return found;
  }
  return std::nullopt;
}

TEST(BridgeClock, AStreamsClockReachesACycloneNodeOnDiagnosticsAndTurnsStaleWhenItsWriterStops) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard lidar(unique_name("clock_lidar"));
  sim::StreamSpec spec{.name = lidar.name};
  spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 10));
  sim::SensorInfo sensor;
  sensor.frame_id = "lidar_top";
  sensor.identity.serial = "122233000123";
  spec.sensor = sensor;
  std::optional<sim::Writer> writer;
  {
    auto created = sim::Writer::create(spec);
    ASSERT_TRUE(created) << created.error().message;
    writer.emplace(std::move(*created));
  }
  ASSERT_TRUE(writer->set_clock(tai_clock()));

  Process bridge = start_bridge({"--publish", lidar.name});
  CycloneParticipant node;
  CycloneReader<Diagnostics> diagnostics(node, &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                                         "rt/diagnostics", EndpointQos{.reliable = true, .depth = 10});

  // The error, told in the clock's own words, with the sensor's serial and every value.
  auto seen = wait_for_status(diagnostics, lidar.name, [](const Seen&) { return true; });
  ASSERT_TRUE(seen) << bridge.err();
  EXPECT_EQ(seen->level, 2);  // ERROR
  EXPECT_EQ(seen->message, tai_clock().problem);
  EXPECT_EQ(seen->hardware_id, "122233000123");
  EXPECT_EQ(seen->values["clock_source"], "ptp");
  EXPECT_EQ(seen->values["sync_state"], "locked");
  EXPECT_EQ(seen->values["offset_from_master_ns"], "-42");
  EXPECT_EQ(seen->values["grandmaster_id"], "00a069.fffe.0b552d");
  EXPECT_EQ(seen->values["offset_to_host_ns"], "37000012000");
  EXPECT_EQ(seen->values["spread_ns"], "3000");
  EXPECT_EQ(seen->values["drift_ppm"], "0.25");
  EXPECT_EQ(seen->values["steps"], "1");
  EXPECT_EQ(seen->values["tai_correction_ns"], "0");
  EXPECT_EQ(seen->values["stamps"], "sensor");

  // The driver fixed it: the next arrays say OK with the summary.
  sim::ClockStatus fixed = tai_clock();
  fixed.tai_correction_ns = 37'000'000'000;
  fixed.offset_to_host_ns = 12'000;
  fixed.stamps = sim::StampClock::sensor_tai_corrected;
  fixed.verdict = sim::ClockVerdict::ok;
  fixed.problem.clear();
  ASSERT_TRUE(writer->set_clock(fixed));
  seen = wait_for_status(diagnostics, lidar.name, [](const Seen& s) { return s.level == 0; });
  ASSERT_TRUE(seen) << bridge.err();
  EXPECT_EQ(seen->message, sim::summary(fixed));
  EXPECT_EQ(seen->values["tai_correction_ns"], "37000000000");

  // The writer stops: STALE, with the last clock still told.
  writer.reset();  // the region stays (StreamGuard removes it), its writer is gone
  seen = wait_for_status(diagnostics, lidar.name, [](const Seen& s) { return s.level == 3; });
  ASSERT_TRUE(seen) << bridge.err();
  EXPECT_NE(seen->message.find("the writer stopped"), std::string::npos) << seen->message;
}

TEST(BridgeClock, TheDiagnosticsWriterAnnouncesDiagnosticArraysRosTypeHash) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard lidar(unique_name("clock_hash"));
  sim::StreamSpec spec{.name = lidar.name};
  spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 10));
  auto writer = sim::Writer::create(spec);
  ASSERT_TRUE(writer) << writer.error().message;

  Process bridge = start_bridge({"--publish", lidar.name});
  CycloneParticipant node;
  CycloneReader<Diagnostics> diagnostics(node, &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                                         "rt/diagnostics", EndpointQos{.reliable = true, .depth = 10});
  // A stream whose writer reports no clock is STALE and says so.
  auto seen = wait_for_status(diagnostics, lidar.name, [](const Seen&) { return true; });
  ASSERT_TRUE(seen) << bridge.err();
  EXPECT_EQ(seen->level, 3);
  EXPECT_EQ(seen->message, "the writer of " + lidar.name + " reports no clock");
  EXPECT_EQ(seen->hardware_id, lidar.name);

  // The endpoint's USER_DATA names the hash ROS 2 Jazzy computes for the type.
  const dds_entity_t builtin =
      dds_create_reader(node.handle(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  std::string user_data;
  for (int i = 0; i < 3000 && user_data.empty(); ++i) {
    void* samples[16] = {};
    dds_sample_info_t info[16];
    const dds_return_t n = dds_take(builtin, samples, info, 16, 16);
    for (dds_return_t k = 0; k < n; ++k) {
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      if (!info[k].valid_data || std::string(e->topic_name) != "rt/diagnostics") continue;
      void* value = nullptr;
      std::size_t size = 0;
      if (dds_qget_userdata(e->qos, &value, &size) && value != nullptr) {
        user_data.assign(static_cast<const char*>(value), size);
        dds_free(value);
      }
    }
    if (n > 0) dds_return_loan(builtin, samples, n);
    if (user_data.empty()) std::this_thread::sleep_for(10ms);
  }
  dds_delete(builtin);
  EXPECT_EQ(user_data,
            "typehash=RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e;");
}

}  // namespace

int main(int argc, char** argv) { return bridge_test::run_tests(argc, argv); }
