// SPDX-License-Identifier: Apache-2.0
// Issue 21 "Beyond the host", the bridge's part, seen by an independent Cyclone DDS node (types
// from idlc) that joins after the bridge started, as a ROS 2 node on rmw_cyclonedds would: the
// calibration on <stream>/camera_info paired by stamp with the images, the mountings on
// /tf_static, the bridge's participant and endpoints with the USER_DATA rmw reads, and the
// bridge as the node sim_dds_bridge on ros_discovery_info. And the other direction: camera_info
// and /tf_static from ROS 2 become the SIM stream's sensor description.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bridge_test.hpp"
#include "cyclone.hpp"
#include "sim/reader.hpp"
#include "sim/ros2/type_hash.hpp"
#include "sim/writer.hpp"
#include "sim_test/network.hpp"
#include "sim_test/process.hpp"
#include "sim_test/streams.hpp"

namespace {

using namespace bridge_test;
using Gid = std::array<std::uint8_t, 16>;

constexpr EndpointQos latched{.reliable = true, .transient_local = true, .depth = 10};
constexpr EndpointQos deep{.depth = 100};  // keeps what arrives until the test takes it

sim::SensorInfo camera_sensor() {
  sim::SensorInfo s;
  s.frame_id = "camera_front_optical";
  s.mounting = sim::Mounting{{1.25, 0.0, 1.5}, {-0.5, 0.5, -0.5, 0.5}};
  sim::CameraCalibration c;
  c.width = 16;
  c.height = 12;
  c.d = {-0.25, 0.125, 0.0, 0.0, 0.0};
  c.k = {500.5, 0, 8.25, 0, 501.5, 6.5, 0, 0, 1};
  c.p = {500.5, 0, 8.25, 0, 0, 501.5, 6.5, 0, 0, 0, 1, 0};
  s.calibration = c;
  return s;
}

sim::SensorInfo lidar_sensor() {
  sim::SensorInfo s;
  s.frame_id = "lidar_top";
  s.mounting = sim::Mounting{{0.0, 0.0, 1.75}, {0, 0, 0, 1}};
  return s;
}

Gid gid_of(const dds_guid_t& guid) {
  Gid gid{};
  std::memcpy(gid.data(), guid.v, 16);
  return gid;
}

std::string user_data(const dds_qos_t* qos) {
  void* value = nullptr;
  std::size_t size = 0;
  if (!dds_qget_userdata(qos, &value, &size) || value == nullptr) return {};
  std::string text(static_cast<const char*>(value), size);
  dds_free(value);
  return text;
}

// What Cyclone's builtin topics tell about one remote endpoint.
struct Endpoint {
  Gid gid;
  Gid participant;
  std::string user_data;
};

// Reads DCPSPublication until a writer of `topic` is announced; nullopt after the hang guard.
std::optional<Endpoint> find_publication(const CycloneParticipant& p, const std::string& topic) {
  const dds_entity_t reader = dds_create_reader(p.handle(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  std::optional<Endpoint> found;
  for (int i = 0; i < 3000 && !found; ++i) {
    void* samples[16] = {};
    dds_sample_info_t info[16];
    const dds_return_t n = dds_take(reader, samples, info, 16, 16);
    for (dds_return_t k = 0; k < n; ++k) {
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      if (info[k].valid_data && e->topic_name != nullptr && topic == e->topic_name) {
        found = Endpoint{gid_of(e->key), gid_of(e->participant_key), user_data(e->qos)};
      }
    }
    if (n > 0) dds_return_loan(reader, samples, n);
    if (!found) std::this_thread::sleep_for(10ms);
  }
  dds_delete(reader);
  return found;
}

// The USER_DATA of the participant `key`, from DCPSParticipant.
std::string participant_user_data(const CycloneParticipant& p, const Gid& key) {
  const dds_entity_t reader = dds_create_reader(p.handle(), DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
  std::optional<std::string> found;
  for (int i = 0; i < 3000 && !found; ++i) {
    void* samples[16] = {};
    dds_sample_info_t info[16];
    const dds_return_t n = dds_take(reader, samples, info, 16, 16);
    for (dds_return_t k = 0; k < n; ++k) {
      const auto* e = static_cast<const dds_builtintopic_participant_t*>(samples[k]);
      if (info[k].valid_data && gid_of(e->key) == key) found = user_data(e->qos);
    }
    if (n > 0) dds_return_loan(reader, samples, n);
    if (!found) std::this_thread::sleep_for(10ms);
  }
  dds_delete(reader);
  return found.value_or("");
}

bool is_rihs01_user_data(const std::string& text) {
  const std::string prefix = "typehash=RIHS01_";
  return text.size() == prefix.size() + 64 + 1 && text.rfind(prefix, 0) == 0 && text.back() == ';' &&
         text.find_first_not_of("0123456789abcdef", prefix.size()) == prefix.size() + 64;
}

// The mountings of the next /tf_static message: child frame → (parent frame, z); nothing when no
// message came.
std::optional<std::map<std::string, std::pair<std::string, double>>> take_mountings(
    CycloneReader<TfMessage>& tf) {
  std::map<std::string, std::pair<std::string, double>> mounted;
  const bool taken = tf.take([&](const TfMessage& m) {
    for (std::uint32_t i = 0; i < m.transforms._length; ++i) {
      const auto& t = m.transforms._buffer[i];
      mounted[t.child_frame_id] = {t.header.frame_id, t.transform.translation.z};
    }
  });
  if (!taken) return std::nullopt;
  return mounted;
}

// Takes ros_discovery_info messages until one says the participant `participant` has the node
// /sim_dds_bridge owning the writer `writer`; false when 50 messages did not (or none came).
bool names_bridge_node(CycloneReader<Graph>& graph, const Gid& participant, const Gid& writer) {
  bool found = false;
  for (int i = 0; i < 50 && !found; ++i) {
    if (!graph.take([&](const Graph& g) {
          if (gid_of(reinterpret_cast<const dds_guid_t&>(g.gid.data)) != participant) return;
          for (std::uint32_t n = 0; n < g.node_entities_info_seq._length; ++n) {
            const auto& node_info = g.node_entities_info_seq._buffer[n];
            if (std::string(node_info.node_name) != "sim_dds_bridge") continue;
            EXPECT_STREQ(node_info.node_namespace, "/");
            for (std::uint32_t w = 0; w < node_info.writer_gid_seq._length; ++w) {
              Gid gid;
              std::memcpy(gid.data(), node_info.writer_gid_seq._buffer[w].data, 16);
              if (gid == writer) found = true;
            }
          }
        })) {
      break;
    }
  }
  return found;
}

// A ROS 2 camera's CameraInfo for `image`: its frame and size, plumb_bob, an identity
// rectification and the camera matrix `k` (the projection too when `p` is given).
struct CameraInfoMessage {
  std::vector<double> d;
  CameraInfo info{};
  CameraInfoMessage(const Image& image, const std::array<double, 9>& k, std::vector<double> distortion,
                    const std::optional<std::array<double, 12>>& p = std::nullopt)
      : d(std::move(distortion)) {
    info.header.frame_id = image.header.frame_id;
    info.width = image.width;
    info.height = image.height;
    info.distortion_model = const_cast<char*>("plumb_bob");
    info.d._buffer = d.data();
    info.d._length = info.d._maximum = static_cast<std::uint32_t>(d.size());
    std::memcpy(info.k, k.data(), sizeof info.k);
    const double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::memcpy(info.r, r, sizeof r);
    if (p) std::memcpy(info.p, p->data(), sizeof info.p);
  }
  CameraInfoMessage(const CameraInfoMessage&) = delete;  // the message points into its own d
  CameraInfoMessage& operator=(const CameraInfoMessage&) = delete;
};

// Publishes the image and its CameraInfo with rising stamps, 20 a second, until the SIM stream
// `stream`'s description satisfies `enough`; that description, or the last one seen (or none)
// after 600 pairs (a hang guard, not a timing check).
template <typename Enough>
std::optional<sim::SensorInfo> publish_until_described(CycloneWriter& images, Image& image,
                                                       CycloneWriter& infos, CameraInfo& info,
                                                       const std::string& stream, Enough enough) {
  std::optional<sim::SensorInfo> described;
  for (int n = 0; n < 600 && !(described && enough(*described)); ++n) {
    image.header.stamp = info.header.stamp = {1'700'000'000 + n, 0};
    images.write(&image);
    infos.write(&info);
    std::this_thread::sleep_for(50ms);
    if (auto status = sim::inspect(stream); status && status->sensor) described = status->sensor;
  }
  return described;
}

TEST(BridgeGraph, ALateRos2NodeGetsCalibrationMountingsUserDataAndTheBridgeAsANode) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard camera(unique_name("cam"));
  StreamGuard lidar(unique_name("lidar"));
  sim::StreamSpec camera_spec{.name = camera.name};
  camera_spec.layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::bgr8));
  camera_spec.sensor = camera_sensor();
  sim::StreamSpec lidar_spec{.name = lidar.name};
  lidar_spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 100));
  lidar_spec.sensor = lidar_sensor();
  FramePump camera_frames(camera_spec);
  FramePump lidar_frames(lidar_spec);
  ASSERT_TRUE(camera_frames.ok()) << camera_frames.error();
  ASSERT_TRUE(lidar_frames.ok()) << lidar_frames.error();

  Process bridge = start_bridge({"--publish", camera.name, "--publish", lidar.name});
  // The bridge has read both descriptions (its /tf_static holds both) before the node joins.
  ASSERT_FALSE(wait_counter(bridge, "/tf_static", "bridged", 2).empty()) << bridge.err();

  CycloneParticipant node;
  CycloneReader<Image> images(node, &sensor_msgs_msg_dds__Image__desc, "rt" + camera.name + "/image_raw", deep);
  CycloneReader<CameraInfo> infos(node, &sensor_msgs_msg_dds__CameraInfo__desc,
                                  "rt" + camera.name + "/camera_info", deep);
  CycloneReader<TfMessage> tf(node, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched);
  CycloneReader<Graph> graph(node, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                             "ros_discovery_info", latched);

  // The calibration beside every image: the same stamp and frame_id.
  std::map<std::int64_t, std::string> image_frames;
  for (int n = 0; n < 10; ++n) {
    ASSERT_TRUE(images.take([&](const Image& i) { image_frames[stamp_of(i.header)] = i.header.frame_id; }))
        << bridge.err();
  }
  int paired = 0;
  for (int n = 0; n < 10; ++n) {
    ASSERT_TRUE(infos.take([&](const CameraInfo& info) {
      const sim::CameraCalibration expected = *camera_sensor().calibration;
      EXPECT_STREQ(info.header.frame_id, "camera_front_optical");
      EXPECT_EQ(info.width, 16u);
      EXPECT_EQ(info.height, 12u);
      EXPECT_STREQ(info.distortion_model, "plumb_bob");
      ASSERT_EQ(info.d._length, expected.d.size());
      for (int k = 0; k < 9; ++k) EXPECT_EQ(info.k[k], expected.k[k]) << k;
      for (int k = 0; k < 12; ++k) EXPECT_EQ(info.p[k], expected.p[k]) << k;
      auto image = image_frames.find(stamp_of(info.header));
      if (image != image_frames.end()) {
        ++paired;
        EXPECT_EQ(image->second, "camera_front_optical");
      }
    })) << bridge.err();
  }
  EXPECT_GT(paired, 0) << "no CameraInfo had the stamp of an image";

  // /tf_static: one message with both mountings, though the node joined later.
  auto mounted = take_mountings(tf);
  ASSERT_TRUE(mounted) << bridge.err();
  EXPECT_EQ((*mounted)["camera_front_optical"], std::make_pair(std::string("base_link"), 1.5));
  EXPECT_EQ((*mounted)["lidar_top"], std::make_pair(std::string("base_link"), 1.75));

  // USER_DATA: the participant is in the ROS 2 graph, each endpoint names its type hash.
  const auto info_writer = find_publication(node, "rt" + camera.name + "/camera_info");
  ASSERT_TRUE(info_writer);
  EXPECT_EQ(info_writer->user_data,
            "typehash=" + std::string(sim::ros2::rihs01_type_hash("sensor_msgs/msg/CameraInfo")) + ";");
  EXPECT_TRUE(is_rihs01_user_data(info_writer->user_data)) << info_writer->user_data;
  const auto image_writer = find_publication(node, "rt" + camera.name + "/image_raw");
  ASSERT_TRUE(image_writer);
  EXPECT_TRUE(is_rihs01_user_data(image_writer->user_data)) << image_writer->user_data;
  EXPECT_NE(participant_user_data(node, info_writer->participant).find("enclave=/;"), std::string::npos);

  // ros_discovery_info: the node sim_dds_bridge of that participant, owning the camera_info writer.
  EXPECT_TRUE(names_bridge_node(graph, info_writer->participant, info_writer->gid))
      << "no ros_discovery_info names sim_dds_bridge with the camera_info writer";
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

// Review turn 4 L9: `ros2 topic echo <ns>/camera_info` alone (nobody reads the images) gets the
// calibration, one per frame, with the frame's stamp.
TEST(BridgeGraph, AReaderOfCameraInfoAloneGetsTheCalibration) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard camera(unique_name("cam_info_only"));
  sim::StreamSpec spec{.name = camera.name};
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::bgr8));
  spec.sensor = camera_sensor();
  FramePump frames(spec);
  ASSERT_TRUE(frames.ok()) << frames.error();
  Process bridge = start_bridge({"--publish", camera.name});
  ASSERT_FALSE(wait_counter(bridge, "/tf_static", "bridged", 1).empty()) << bridge.err();

  CycloneParticipant node;
  CycloneReader<CameraInfo> infos(node, &sensor_msgs_msg_dds__CameraInfo__desc,
                                  "rt" + camera.name + "/camera_info", deep);
  std::set<std::int64_t> stamps;
  for (int n = 0; n < 3; ++n) {
    ASSERT_TRUE(infos.take([&](const CameraInfo& info) {
      EXPECT_STREQ(info.header.frame_id, "camera_front_optical");
      EXPECT_EQ(info.width, 16u);
      EXPECT_EQ(info.k[0], 500.5);
      stamps.insert(stamp_of(info.header));
    })) << "no CameraInfo without an image reader: " << bridge.err();
  }
  EXPECT_EQ(stamps.size(), 3u) << "one CameraInfo per frame, each with its frame's stamp";
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

// Review turn 4 L2: with --frame-id S=F the images say F, so /tf_static mounts F (not the
// description's frame, which then was in no message).
TEST(BridgeGraph, AFrameIdOverrideIsTheChildOnTfStaticToo) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard camera(unique_name("cam_renamed"));
  sim::StreamSpec spec{.name = camera.name};
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(16, 12, sim::PixelFormat::bgr8));
  spec.sensor = camera_sensor();
  FramePump frames(spec);
  ASSERT_TRUE(frames.ok()) << frames.error();
  Process bridge = start_bridge({"--publish", camera.name, "--frame-id", camera.name + "=renamed_optical"});
  CycloneParticipant node;
  CycloneReader<TfMessage> tf(node, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched);
  const auto mounted = take_mountings(tf);
  ASSERT_TRUE(mounted) << bridge.err();
  EXPECT_EQ(mounted->count("renamed_optical"), 1u) << bridge.err();
  EXPECT_EQ(mounted->count("camera_front_optical"), 0u);
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

TEST(BridgeGraph, CameraInfoAndTfStaticFromRos2BecomeTheStreamsSensorDescription) {
  SKIP_WITHOUT_NETWORK();
  const std::string ns = unique_name("remote_cam");
  StreamGuard local(unique_name("remote_cam_local"));
  Process bridge = start_bridge({"--subscribe", ns + "/image_raw", "--as", local.name});
  CycloneParticipant node;
  CycloneWriter tf(node, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched);
  CycloneWriter images(node, &sensor_msgs_msg_dds__Image__desc, "rt" + ns + "/image_raw");
  CycloneWriter infos(node, &sensor_msgs_msg_dds__CameraInfo__desc, "rt" + ns + "/camera_info");

  geometry_msgs_msg_dds__TransformStamped_ mounting{};
  mounting.header.frame_id = const_cast<char*>("base_link");
  mounting.child_frame_id = const_cast<char*>("remote_cam_optical");
  mounting.transform.translation = {0.5, -0.25, 2.0};
  mounting.transform.rotation = {0, 0, 0, 1};
  TfMessage tf_message{};
  tf_message.transforms._buffer = &mounting;
  tf_message.transforms._length = tf_message.transforms._maximum = 1;
  tf.write(&tf_message);  // latched: the bridge gets it whenever it matches

  ImageMessage image(8, 6, "mono8", 8, 9, "remote_cam_optical");
  CameraInfoMessage info(image.image, {40.5, 0, 4, 0, 41.5, 3, 0, 0, 1}, {0.1, -0.05, 0, 0, 0},
                         std::array<double, 12>{40.5, 0, 4, 0, 0, 41.5, 3, 0, 0, 0, 1, 0});
  const auto described = publish_until_described(
      images, image.image, infos, info.info, local.name,
      [](const sim::SensorInfo& s) { return s.calibration && s.mounting; });
  ASSERT_TRUE(described && described->calibration && described->mounting) << bridge.err();
  EXPECT_EQ(described->frame_id, "remote_cam_optical");
  EXPECT_EQ(described->parent_frame, "base_link");
  EXPECT_EQ(described->mounting->translation, (std::array<double, 3>{0.5, -0.25, 2.0}));
  EXPECT_EQ(described->calibration->k, (std::array<double, 9>{40.5, 0, 4, 0, 41.5, 3, 0, 0, 1}));
  EXPECT_EQ(described->calibration->d, (std::vector<double>{0.1, -0.05, 0, 0, 0}));
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

// Review turn 4 M1-M4: an uncalibrated camera (CameraInfo with K all zero and no
// distortion_model, as camera drivers send without a calibration file) whose frame has a '-' and
// a '.' and whose mounting has a hand-typed quaternion: the stream gets the frame and the
// mounting (without the calibration), and keeps flowing after its region is replaced for a new
// image size.
TEST(BridgeGraph, AnUncalibratedCameraKeepsItsMountingAndItsStreamSurvivesANewImageSize) {
  SKIP_WITHOUT_NETWORK();
  const std::string ns = unique_name("raw_cam");
  StreamGuard local(unique_name("raw_cam_local"));
  Process bridge = start_bridge({"--subscribe", ns + "/image_raw", "--as", local.name});
  CycloneParticipant node;
  CycloneWriter tf(node, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", latched);
  CycloneWriter images(node, &sensor_msgs_msg_dds__Image__desc, "rt" + ns + "/image_raw");
  CycloneWriter infos(node, &sensor_msgs_msg_dds__CameraInfo__desc, "rt" + ns + "/camera_info");

  geometry_msgs_msg_dds__TransformStamped_ mounting{};
  mounting.header.frame_id = const_cast<char*>("base_link");
  mounting.child_frame_id = const_cast<char*>("usb-cam.optical");
  mounting.transform.translation = {0.5, -0.25, 2.0};
  mounting.transform.rotation = {0.7071, 0, 0, 0.7071};  // typed with four decimals
  TfMessage tf_message{};
  tf_message.transforms._buffer = &mounting;
  tf_message.transforms._length = tf_message.transforms._maximum = 1;
  tf.write(&tf_message);

  ImageMessage small(8, 6, "mono8", 8, 9, "usb-cam.optical");
  CameraInfoMessage uncalibrated(small.image, {}, {});
  uncalibrated.info.distortion_model = const_cast<char*>("");
  const auto described = publish_until_described(images, small.image, infos, uncalibrated.info, local.name,
                                                 [](const sim::SensorInfo& s) { return s.mounting.has_value(); });
  EXPECT_TRUE(described && described->mounting) << bridge.err();
  if (described && described->mounting) {
    EXPECT_EQ(described->frame_id, "usb-cam.optical");
    EXPECT_EQ(described->parent_frame, "base_link");
    EXPECT_NEAR(described->mounting->rotation[0], std::sqrt(0.5), 1e-12) << "stored normalised";
    EXPECT_FALSE(described->calibration) << "an all-zero K is no calibration";
  }

  // A larger image replaces the region; the stream carries on with its description.
  ImageMessage large(16, 12, "mono8", 16, 5, "usb-cam.optical");
  CameraInfoMessage large_info(large.image, {}, {});
  large_info.info.distortion_model = const_cast<char*>("");
  std::optional<sim::StreamStatus> status;
  for (int n = 0; n < 600; ++n) {  // a hang guard, not a timing check
    large.image.header.stamp = large_info.info.header.stamp = {1'800'000'000 + n, 0};
    images.write(&large.image);
    infos.write(&large_info.info);
    std::this_thread::sleep_for(50ms);
    if (auto got = sim::inspect(local.name)) status = *got;
    if (status && status->layout.kind == sim::LayoutKind::image && status->layout.image.width == 16 &&
        status->frames_this_writer > 0) {
      break;
    }
  }
  ASSERT_TRUE(status) << bridge.err();
  EXPECT_EQ(status->layout.image.width, 16u) << "the stream stopped at the new image size: " << bridge.err();
  EXPECT_GT(status->frames_this_writer, 0u) << bridge.err();
  ASSERT_TRUE(status->sensor && status->sensor->mounting) << bridge.err();
  EXPECT_EQ(status->sensor->frame_id, "usb-cam.optical");
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

// Review H1: the bridge's own messages are never taken back. Its own /tf_static names the frame
// of the images it subscribes; that mounting must not come back as the subscribed stream's.
TEST(BridgeGraph, TheBridgeNeverReadsItsOwnTfStaticBack) {
  SKIP_WITHOUT_NETWORK();
  StreamGuard lidar(unique_name("own_lidar"));
  sim::StreamSpec spec{.name = lidar.name};
  spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::xyz32, 10));
  spec.sensor = lidar_sensor();  // frame lidar_top, mounted 1.75 m up
  FramePump frames(spec);
  ASSERT_TRUE(frames.ok()) << frames.error();
  const std::string ns = unique_name("own_cam");
  StreamGuard local(unique_name("own_cam_local"));
  Process bridge = start_bridge({"--publish", lidar.name, "--subscribe", ns + "/image_raw", "--as", local.name});
  ASSERT_FALSE(wait_counter(bridge, "/tf_static", "bridged", 1).empty()) << bridge.err();

  CycloneParticipant node;
  CycloneWriter images(node, &sensor_msgs_msg_dds__Image__desc, "rt" + ns + "/image_raw");
  CycloneWriter infos(node, &sensor_msgs_msg_dds__CameraInfo__desc, "rt" + ns + "/camera_info");
  // The frame the bridge itself mounts.
  ImageMessage image(4, 2, "mono8", 4, 1, "lidar_top");
  CameraInfoMessage info(image.image, {4, 0, 2, 0, 4, 1, 0, 0, 1}, {});
  const auto described =
      publish_until_described(images, image.image, infos, info.info, local.name,
                              [](const sim::SensorInfo& s) { return s.calibration.has_value(); });
  ASSERT_TRUE(described && described->calibration) << bridge.err();
  EXPECT_FALSE(described->mounting.has_value()) << "the bridge read its own /tf_static back";
  bridge.signal(SIGTERM);
  EXPECT_EQ(bridge.wait(), 0) << bridge.err();
}

}  // namespace

int main(int argc, char** argv) { return bridge_test::run_tests(argc, argv); }
