// SPDX-License-Identifier: Apache-2.0
// The defects an adversarial review of the bridge found (the review itself is not in this repository),
// each reproduced the way the review found it: the real bridge process, a Cyclone DDS peer with
// the ROS 2 types from idlc, in a private network namespace.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <cstring>
#include <string>
#include <vector>

#include "bridge_test.hpp"
#include "cyclone.hpp"
#include "sim/reader.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

using namespace bridge_test;

// H1, L1, L2: configurations the bridge used to accept silently.
TEST(BridgeReview, RefusesLoopsDuplicatesAndImpossibleRatesWithOneSentence) {
  const std::vector<std::vector<std::string>> bad = {
      {"--publish", "/a", "--subscribe", "/a"},                      // H1: one stream both ways
      {"--publish", "/a", "--subscribe", "/b", "--as", "/a"},        // H1: into the published stream
      {"--publish", "/cam", "--subscribe", "/cam/image_raw", "--as", "/x"},  // H1: its own topic
      {"--publish", "/a", "--publish", "/a"},                        // L1
      {"--subscribe", "/a", "--subscribe", "/a"},
      {"--subscribe", "/a", "--as", "/x", "--subscribe", "/b", "--as", "/x"},
      {"--subscribe", "/a", "--as", "/b=/x"},
      {"--subscribe", "/a", "--as", "/a=/x", "--as", "/a=/y"},
      {"--publish", "/a", "--frame-id", "/a=x", "--frame-id", "/a=y"},
      {"--publish", "/a", "--max-rate", "/a=1e-12"},                 // L2
      {"--publish", "/a", "--max-rate", "/a=inf"},
  };
  for (const auto& args : bad) {
    std::vector<std::string> argv = {bridge_tool};
    argv.insert(argv.end(), args.begin(), args.end());
    const auto r = sim::testing::run(argv);
    std::string command;
    for (const auto& a : args) command += a + " ";
    EXPECT_EQ(r.code, 2) << command;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << command << ": " << r.err;
  }
}

struct CloudMessage {
  std::vector<std::uint8_t> data;
  std::vector<sensor_msgs_msg_dds__PointField_> fields;
  Cloud cloud{};
  CloudMessage(std::uint32_t points, std::uint32_t point_step,
               std::vector<sensor_msgs_msg_dds__PointField_> f)
      : data(std::size_t{points} * point_step), fields(std::move(f)) {
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i);
    cloud.header.stamp = {1'700'000'000, 0};
    cloud.header.frame_id = const_cast<char*>("lidar");
    cloud.height = 1;
    cloud.width = points;
    cloud.fields._buffer = fields.data();
    cloud.fields._length = cloud.fields._maximum = static_cast<std::uint32_t>(fields.size());
    cloud.point_step = point_step;
    cloud.row_step = points * point_step;
    cloud.data._buffer = data.data();
    cloud.data._length = cloud.data._maximum = static_cast<std::uint32_t>(data.size());
  }
};

sensor_msgs_msg_dds__PointField_ field(const char* name, std::uint32_t offset, std::uint8_t type) {
  return {const_cast<char*>(name), offset, type, 1};
}

// M2: the malformed cloud used to replace the region (a new layout, no frames) before it was dropped.
TEST(BridgeReview, AMalformedCloudLeavesTheStreamAndItsLastFrameAsTheyWere) {
  SKIP_WITHOUT_NETWORK();
  Subscription s("m2", &sensor_msgs_msg_dds__PointCloud2__desc);
  auto& [topic, local, bridge, participant, writer] = s;
  ASSERT_TRUE(writer.wait_matched()) << bridge.err();

  CloudMessage good(10, 12, {field("x", 0, 7), field("y", 4, 7), field("z", 8, 7)});
  writer.write(&good.cloud);
  auto reader = open_when_created(local.name);
  ASSERT_TRUE(reader) << bridge.err();
  ASSERT_TRUE(publish_until_seen(writer, &good.cloud, *reader)) << bridge.err();
  auto before = sim::inspect(local.name);
  ASSERT_TRUE(before);

  CloudMessage bad(50, 12, {field("a", 0, 7), field("b", 4, 7), field("c", 8, 7)});
  for (int i = 0; i < 10; ++i) writer.write(&bad.cloud);
  ASSERT_FALSE(wait_counter(bridge, topic, "malformed", 1).empty()) << bridge.err();
  auto after = sim::inspect(local.name);
  ASSERT_TRUE(after);
  EXPECT_EQ(after->layout, before->layout) << "the region was replaced";
  EXPECT_EQ(after->writer_start_realtime_ns, before->writer_start_realtime_ns);
  // Its newest frame is still a good cloud (more good copies may have arrived meanwhile).
  auto fresh = sim::Reader::open(local.name);
  ASSERT_TRUE(fresh);
  std::vector<std::byte> buffer(fresh->capacity());
  sim::FrameInfo newest;
  ASSERT_EQ(fresh->read(buffer, newest), sim::ReadStatus::new_frame);
  EXPECT_EQ(newest.size, good.data.size());
  EXPECT_EQ(std::memcmp(buffer.data(), good.data.data(), good.data.size()), 0);
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  EXPECT_NE(bridge.err().find("no x, y and z fields"), std::string::npos) << bridge.err();
}

// M3: 1-byte points whose x, y and z are one INT8 became 24-byte SIM points (a 96× region).
TEST(BridgeReview, ACloudThatWouldGrowManyTimesIsRefusedBeforeAnyRegionIsMade) {
  SKIP_WITHOUT_NETWORK();
  Subscription s("m3", &sensor_msgs_msg_dds__PointCloud2__desc,
                 {.bridge_options = {"--reliable-subscribe"}, .writer_qos = {.reliable = true}});
  auto& [topic, local, bridge, participant, writer] = s;
  ASSERT_TRUE(writer.wait_matched()) << bridge.err();
  CloudMessage amplifier(200'000, 1, {field("x", 0, 1), field("y", 0, 1), field("z", 0, 1)});
  writer.write(&amplifier.cloud);
  ASSERT_FALSE(wait_counter(bridge, topic, "malformed", 1).empty()) << bridge.err();
  EXPECT_FALSE(sim::Reader::open(local.name)) << "a region was made for the cloud";
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  EXPECT_NE(bridge.err().find("times the message"), std::string::npos) << bridge.err();
}

// M4: --reliable (for publishing) also made every subscription reliable, which never matched a
// best-effort (SensorDataQoS) publisher.
TEST(BridgeReview, PublishingReliablyStillReadsBestEffortPublishers) {
  SKIP_WITHOUT_NETWORK();
  // The writer is best effort, as SensorDataQoS publishers are.
  Subscription s("m4_be", &sensor_msgs_msg_dds__Image__desc, {.bridge_options = {"--reliable"}});
  auto& [topic, local, bridge, participant, writer] = s;
  ASSERT_TRUE(writer.wait_matched()) << bridge.err();
  ImageMessage m(4, 2, "mono8", 4);
  writer.write(&m.image);
  auto reader = open_when_created(local.name);
  ASSERT_TRUE(reader) << bridge.err();
  EXPECT_TRUE(publish_until_seen(writer, &m.image, *reader)) << bridge.err();
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
}

// M4: a writer that cannot match used to be silent; now each is told in one sentence.
TEST(BridgeReview, AReliableSubscriptionSaysWhyBestEffortAndXcdr2WritersDoNotMatch) {
  SKIP_WITHOUT_NETWORK();
  const std::string best_effort = unique_name("m4_qos");
  const std::string xcdr2 = unique_name("m4_xcdr2");
  StreamGuard a(unique_name("m4_qos_local"));
  StreamGuard b(unique_name("m4_xcdr2_local"));
  Process bridge = start_bridge({"--reliable-subscribe", "--subscribe", best_effort, "--as", a.name,
                                 "--subscribe", xcdr2, "--as", b.name});
  CycloneParticipant participant;
  CycloneWriter w1(participant, &sensor_msgs_msg_dds__Image__desc, "rt" + best_effort);
  CycloneWriter w2(participant, &sensor_msgs_msg_dds__Image__desc, "rt" + xcdr2,
                   EndpointQos{.reliable = true, .xcdr2 = true});
  (void)wait_until_told(bridge, {"does not match --reliable-subscribe", "sends only XCDR2"});
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  EXPECT_NE(bridge.err().find(best_effort + ": a writer publishes best effort"), std::string::npos)
      << bridge.err();
  EXPECT_NE(bridge.err().find(xcdr2 + ": a writer sends only XCDR2"), std::string::npos) << bridge.err();
}

// L3: only the last problem of a status period used to be told. L6 and L7: an odd-width 4:2:2
// image and a negative stamp used to become SIM frames.
TEST(BridgeReview, EveryDistinctProblemOfOnePeriodIsTold) {
  SKIP_WITHOUT_NETWORK();
  // Reliable both ways: the three messages arrive back to back, and are taken within one period.
  Subscription s("l3", &sensor_msgs_msg_dds__Image__desc,
                 {.bridge_options = {"--reliable-subscribe"}, .writer_qos = {.reliable = true}});
  auto& [topic, local, bridge, participant, writer] = s;
  ASSERT_TRUE(writer.wait_matched()) << bridge.err();
  ImageMessage odd(3, 1, "yuv422", 6);
  ImageMessage negative(4, 2, "mono8", 4);
  negative.image.header.stamp.sec = -5;
  ImageMessage short_step(4, 2, "mono8", 4);
  short_step.image.step = 5;
  for (Image* m : {&odd.image, &negative.image, &short_step.image}) writer.write(m);
  ASSERT_FALSE(wait_counter(bridge, topic, "malformed", 3).empty()) << bridge.err();
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  const std::string err = bridge.err();
  EXPECT_NE(err.find("odd width 3"), std::string::npos) << err;
  EXPECT_NE(err.find("before 1970"), std::string::npos) << err;
  EXPECT_NE(err.find("step × height"), std::string::npos) << err;
  EXPECT_FALSE(sim::Reader::open(local.name)) << "a bad image became a SIM frame";
}

// L8: a later writer of another type on a subscribed topic was never bridged and never told.
TEST(BridgeReview, AWriterOfAnotherTypeOnASubscribedTopicIsTold) {
  SKIP_WITHOUT_NETWORK();
  Subscription s("l8", &sensor_msgs_msg_dds__Image__desc);
  auto& [topic, local, bridge, participant, images] = s;
  ASSERT_TRUE(images.wait_matched()) << bridge.err();
  CycloneParticipant other;
  CycloneWriter clouds(other, &sensor_msgs_msg_dds__PointCloud2__desc, "rt" + topic);
  const std::string told = "a writer publishes sensor_msgs::msg::dds_::PointCloud2_";
  (void)wait_until_told(bridge, {told});
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  EXPECT_NE(bridge.err().find(told), std::string::npos) << bridge.err();
}

// L4: the compressed topic's entry said "connected":false and "frames_seen":0 while it sent,
// and the last report was printed while a write was still in flight.
TEST(BridgeReview, TheCompressedTopicAndTheFinalReportCountWhatWasSent) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard stream(unique_name("l4"));
  FramePump pump({.name = stream.name,
                  .layout = sim::Layout::of(sim::ImageLayout::packed(32, 24, sim::PixelFormat::bgr8))});
  ASSERT_TRUE(pump.ok()) << pump.error();
  Process bridge = start_bridge({"--publish", stream.name, "--compress", stream.name + "=jpeg"});
  CycloneParticipant participant;
  CycloneReader<Compressed> jpegs(participant, &sensor_msgs_msg_dds__CompressedImage__desc,
                                  "rt" + stream.name + "/image_raw/compressed");
  ASSERT_TRUE(jpegs.take([](const Compressed&) {})) << bridge.err();
  const std::string compressed_topic = stream.name + "/image_raw/compressed";
  const std::string line = wait_counter(bridge, compressed_topic, "bridged", 1);
  ASSERT_FALSE(line.empty()) << bridge.err();
  const auto at = line.find("\"topic\":\"" + compressed_topic + "\"");
  EXPECT_NE(line.find("\"connected\":true", at), std::string::npos) << line;
  EXPECT_GE(json_counter(line, compressed_topic, "frames_seen"), 1) << line;
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0);
  std::string last;
  for (std::string_view rest = bridge.out(); !rest.empty();) {
    const auto nl = rest.find('\n');
    if (rest.substr(0, nl).find("\"topics\"") != std::string_view::npos) last = rest.substr(0, nl);
    rest = nl == std::string_view::npos ? std::string_view{} : rest.substr(nl + 1);
  }
  const std::string raw_topic = stream.name + "/image_raw";
  EXPECT_EQ(json_counter(last, raw_topic, "serialized"),
            json_counter(last, raw_topic, "bridged") + json_counter(last, raw_topic, "failed") +
                json_counter(last, raw_topic, "torn"))
      << last;
}

// The ParticipantEntitiesInfo an rmw publishes for a participant with one node.
struct GraphMessage {
  rmw_dds_common_msg_dds__NodeEntitiesInfo_ node{};
  std::vector<rmw_dds_common_msg_dds__Gid_> readers;
  rmw_dds_common_msg_dds__ParticipantEntitiesInfo_ info{};
  GraphMessage(dds_entity_t participant, std::vector<dds_entity_t> reader_entities) {
    dds_guid_t guid;
    dds_get_guid(participant, &guid);
    std::memcpy(info.gid.data, guid.v, 16);
    for (dds_entity_t r : reader_entities) {
      dds_get_guid(r, &guid);
      rmw_dds_common_msg_dds__Gid_ gid;
      std::memcpy(gid.data, guid.v, 16);
      readers.push_back(gid);
    }
    std::strcpy(node.node_namespace, "/");
    std::strcpy(node.node_name, "viewer");
    node.reader_gid_seq._buffer = readers.data();
    node.reader_gid_seq._length = node.reader_gid_seq._maximum = static_cast<std::uint32_t>(readers.size());
    info.node_entities_info_seq._buffer = &node;
    info.node_entities_info_seq._length = info.node_entities_info_seq._maximum = 1;
  }
};

// M1: a Cyclone DDS (rmw_cyclonedds) reader deleted while its participant lives stayed matched:
// the bridge went on serializing and sending to it. A ROS 2 node says so on ros_discovery_info.
TEST(BridgeReview, AReaderItsRos2NodeDroppedIsNoLongerServed) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard stream(unique_name("m1"));
  FramePump pump({.name = stream.name,
                  .layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::mono8))});
  ASSERT_TRUE(pump.ok()) << pump.error();
  Process bridge = start_bridge({"--publish", stream.name});
  const std::string topic = stream.name + "/image_raw";

  CycloneParticipant node;
  CycloneWriter graph(node, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc, "ros_discovery_info",
                      EndpointQos{.reliable = true, .transient_local = true, .depth = 1});
  std::optional<CycloneReader<Image>> images;
  images.emplace(node, &sensor_msgs_msg_dds__Image__desc, "rt" + topic);
  GraphMessage with_reader(node.handle(), {images->handle()});
  graph.write(&with_reader.info);
  ASSERT_TRUE(images->take([](const Image&) {})) << bridge.err();
  ASSERT_FALSE(wait_counter(bridge, topic, "serialized", 1).empty()) << bridge.err();

  images.reset();  // the subscription goes; the participant (the node) stays
  GraphMessage without_reader(node.handle(), {});
  graph.write(&without_reader.info);
  std::string idle;
  for (int i = 0; i < 300 && idle.empty(); ++i) {  // a hang guard, not a timing check
    auto line = bridge.wait_for_line("\"topics\"");
    if (!line) break;
    if (json_counter(*line, topic, "matched") == 0) idle = *line;
  }
  ASSERT_FALSE(idle.empty()) << "the reader stayed matched\n" << bridge.err();
  // From now on frames are left alone, not serialized.
  const long long serialized = json_counter(idle, topic, "serialized");
  const std::string later = wait_counter(bridge, topic, "no_reader", json_counter(idle, topic, "no_reader") + 5);
  ASSERT_FALSE(later.empty()) << bridge.err();
  EXPECT_EQ(json_counter(later, topic, "serialized"), serialized) << later;
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

// The start-up line names the topics the frames really go to: the stream's name for points,
// <name>/image_raw for images (it used to say "<name>[/image_raw]" for both).
TEST(BridgeReview, TheStartLineNamesTheTopicEachStreamIsPublishedOn) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard lidar(unique_name("start_points"));
  StreamGuard camera(unique_name("start_image"));
  FramePump points({.name = lidar.name, .layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 10))});
  FramePump images({.name = camera.name,
                    .layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::mono8))});
  ASSERT_TRUE(points.ok()) << points.error();
  ASSERT_TRUE(images.ok()) << images.error();
  Process bridge({bridge_tool, "--json", "--status-period", "0.1", "--publish", lidar.name, "--publish", camera.name});
  ASSERT_TRUE(bridge.wait_for_line("\"topics\"")) << bridge.err();
  EXPECT_NE(bridge.err().find(lidar.name + " → DDS rt" + lidar.name + " (domain 0)"), std::string::npos) << bridge.err();
  EXPECT_NE(bridge.err().find(camera.name + " → DDS rt" + camera.name + "/image_raw (domain 0)"), std::string::npos)
      << bridge.err();
  EXPECT_EQ(bridge.err().find("[/image_raw]"), std::string::npos) << bridge.err();
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

}  // namespace

int main(int argc, char** argv) { return bridge_test::run_tests(argc, argv); }
