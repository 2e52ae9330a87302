// SPDX-License-Identifier: Apache-2.0
// The messages beside the frames (CameraInfo, TFMessage) and the RIHS01 type hashes: hashes equal
// to the ones rosidl generated, exact XCDR1 bytes, round trips, one sentence for bad input.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "sim/ros2/decode.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/graph.hpp"
#include "sim/ros2/metadata.hpp"
#include "sim/ros2/type_hash.hpp"

namespace {

using namespace sim;
using namespace sim::ros2;

CameraCalibration some_calibration() {
  CameraCalibration c;
  c.width = 768;
  c.height = 576;
  c.distortion_model = "plumb_bob";
  c.d = {-0.25, 0.07, 0.001, -0.002, 0.0};
  c.k = {610.5, 0, 384.25, 0, 611.75, 288.5, 0, 0, 1};
  c.p = {610.5, 0, 384.25, 0, 0, 611.75, 288.5, 0, 0, 0, 1, 0};
  c.binning_x = 1;
  c.roi = {4, 8, 100, 200, true};
  return c;
}

// Field by field: GCC 12 emits no body for CameraCalibration's defaulted operator== (an undefined
// reference at link time), so it is not used here.
bool same_calibration(const CameraCalibration& a, const CameraCalibration& b) {
  return a.width == b.width && a.height == b.height && a.distortion_model == b.distortion_model &&
         a.d == b.d && a.k == b.k && a.r == b.r && a.p == b.p && a.binning_x == b.binning_x &&
         a.binning_y == b.binning_y && a.roi.x_offset == b.roi.x_offset &&
         a.roi.y_offset == b.roi.y_offset && a.roi.width == b.roi.width &&
         a.roi.height == b.roi.height && a.roi.do_rectify == b.roi.do_rectify;
}

double f64_at(const std::vector<std::byte>& b, std::size_t at) {
  double v;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}

// rosidl's generated *__description.c / *__struct.h of Jazzy and Kilted carry these; the first two
// are also in the reference note (sensor-metadata-ros2-foxglove.md §3).
TEST(Ros2TypeHash, HashesEqualTheValuesRosidlGenerated) {
  EXPECT_EQ(rihs01_type_hash("std_msgs/msg/Header"),
            "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01");
  EXPECT_EQ(rihs01_type_hash("builtin_interfaces/msg/Time"),
            "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197");
  EXPECT_EQ(rihs01_type_hash("sensor_msgs/msg/CameraInfo"),
            "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275");
  EXPECT_EQ(rihs01_type_hash(MessageType::image),
            "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47");
  EXPECT_EQ(rihs01_type_hash(MessageType::compressed_image),
            "RIHS01_15640771531571185e2efc8a100baf923961a4d15d5569652e6cb6691e8e371a");
  EXPECT_EQ(rihs01_type_hash("tf2_msgs/msg/TFMessage"),
            "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087");
  EXPECT_EQ(rihs01_type_hash("rmw_dds_common/msg/Gid"),
            "RIHS01_ab6f21cfbb0a6dbb837161e1110c2051a2850ed9f9c53944d7115d9bcebedf71");
}

TEST(Ros2TypeHash, EveryTypeTheBridgeUsesHasAHashOfSixtyFourHexDigits) {
  for (std::string_view type :
       {"sensor_msgs/msg/PointCloud2", "sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage",
        "sensor_msgs/msg/CameraInfo", "tf2_msgs/msg/TFMessage",
        "rmw_dds_common/msg/ParticipantEntitiesInfo"}) {
    const std::string_view hash = rihs01_type_hash(type);
    ASSERT_EQ(hash.size(), 7u + 64u) << type;
    EXPECT_EQ(hash.substr(0, 7), "RIHS01_") << type;
    EXPECT_EQ(hash.substr(7).find_first_not_of("0123456789abcdef"), std::string_view::npos) << type;
  }
  EXPECT_NE(rihs01_type_hash("sensor_msgs/msg/PointCloud2"), rihs01_type_hash("sensor_msgs/msg/Image"));
  EXPECT_TRUE(rihs01_type_hash("sensor_msgs/msg/Imu").empty());
}

TEST(Ros2TypeHash, TheHashedJsonIsRosidlsCanonicalForm) {
  EXPECT_EQ(type_description_json("builtin_interfaces/msg/Time"),
            R"({"type_description": {"type_name": "builtin_interfaces/msg/Time", "fields": [)"
            R"({"name": "sec", "type": {"type_id": 6, "capacity": 0, "string_capacity": 0, )"
            R"("nested_type_name": ""}}, {"name": "nanosec", "type": {"type_id": 7, "capacity": 0, )"
            R"("string_capacity": 0, "nested_type_name": ""}}]}, "referenced_type_descriptions": []})");
  // Referenced types once each, sorted by name, however deep they are referenced.
  const std::string tf = type_description_json("tf2_msgs/msg/TFMessage");
  std::size_t last = 0;
  for (std::string_view name :
       {"builtin_interfaces/msg/Time", "geometry_msgs/msg/Quaternion", "geometry_msgs/msg/Transform",
        "geometry_msgs/msg/TransformStamped", "geometry_msgs/msg/Vector3", "std_msgs/msg/Header"}) {
    const std::string key = "{\"type_name\": \"" + std::string(name) + "\"";
    const std::size_t at = tf.find(key, tf.find("referenced_type_descriptions"));
    ASSERT_NE(at, std::string::npos) << name;
    EXPECT_GT(at, last) << name;
    EXPECT_EQ(tf.find(key, at + 1), std::string::npos) << name;
    last = at;
  }
}

TEST(Ros2CameraInfo, BytesFollowXcdr1WithDoublesOnEightByteBoundaries) {
  const auto message = encode_camera_info({Time{7, 9}, "cam"}, some_calibration()).value();
  // 00 01 00 00 | sec nanosec | frame_id "cam" (len 4) | height width | "plumb_bob" (len 10)
  // offsets from the origin: 0 sec, 4 nanosec, 8 len, 12 "cam\0", 16 height, 20 width, 24 len,
  // 28..37 "plumb_bob\0", 40 d count, 44 pad, 48 d[0]
  EXPECT_EQ(message[1], std::byte{1});
  std::uint32_t count = 0;
  std::memcpy(&count, message.data() + 4 + 40, 4);
  EXPECT_EQ(count, 5u);
  EXPECT_EQ(f64_at(message, 4 + 48), -0.25);
  EXPECT_EQ(f64_at(message, 4 + 48 + 5 * 8), 610.5);  // k[0]
  // d, k, r, p; binning x y; roi 4 × uint32 and a bool.
  EXPECT_EQ(message.size(), 4u + 48 + 8 * (5 + 9 + 9 + 12) + 8 + 16 + 1);
}

TEST(Ros2CameraInfo, RoundTripsEveryCalibrationField) {
  const CameraCalibration c = some_calibration();
  auto message = encode_camera_info({Time{1700000000, 123456789}, "camera_front_optical"}, c);
  ASSERT_TRUE(message.has_value()) << message.error().message;
  auto back = decode_camera_info(*message);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->header.frame_id, "camera_front_optical");
  EXPECT_EQ(back->header.stamp, (Time{1700000000, 123456789}));
  EXPECT_TRUE(same_calibration(back->calibration, c));
}

TEST(Ros2CameraInfo, EveryTruncationIsDroppedWithASentence) {
  const auto message = encode_camera_info({Time{1, 2}, "cam"}, some_calibration()).value();
  for (std::size_t n = 0; n < message.size(); ++n) {
    auto r = decode_camera_info(std::span(message).first(n));
    ASSERT_FALSE(r.has_value()) << n;
    EXPECT_NE(r.error().message.find("dropped a malformed sensor_msgs/msg/CameraInfo"),
              std::string::npos);
  }
}

TEST(Ros2CameraInfo, TooManyCoefficientsAndNonFiniteValuesAreRefused) {
  CameraCalibration c = some_calibration();
  c.d.assign(max_distortion_coefficients + 1, 0.0);
  EXPECT_FALSE(encode_camera_info({Time{}, "cam"}, c).has_value());
  c.d.assign(max_distortion_coefficients, 0.0);
  auto message = encode_camera_info({Time{}, "cam"}, c).value();
  std::uint32_t too_many = 0x7fffffff;
  std::memcpy(message.data() + 4 + 40, &too_many, 4);
  auto r = decode_camera_info(message);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("distortion coefficients"), std::string::npos);

  c = some_calibration();
  c.k[0] = std::numeric_limits<double>::quiet_NaN();
  auto nan = decode_camera_info(encode_camera_info({Time{}, "cam"}, c).value());
  ASSERT_FALSE(nan.has_value());
  EXPECT_NE(nan.error().message.find("not a finite number"), std::string::npos);
}

TEST(Ros2CameraInfo, TheSiblingTopicReplacesTheLastNameToken) {
  EXPECT_EQ(camera_info_topic_for("/cam/front/image_raw"), "/cam/front/camera_info");
  EXPECT_EQ(camera_info_topic_for("/camera_front/image_raw"), "/camera_front/camera_info");
  EXPECT_EQ(camera_info_topic_for("/camera_front"), "/camera_info");
}

TEST(Ros2CameraInfo, ACompressedImagesSiblingIsTheCameraInfoBesideItsImageTopic) {
  // Review turn 4 L1: image_transport's /compressed is a sub-topic of the image topic.
  EXPECT_EQ(camera_info_topic_for("/cam/image_raw/compressed"), "/cam/camera_info");
  EXPECT_EQ(camera_info_topic_for("/compressed"), "/camera_info");
}

TEST(Ros2CameraInfo, RestampRewritesOnlyTheHeaderStamp) {
  auto message = encode_camera_info({Time{1, 2}, "cam"}, some_calibration()).value();
  ASSERT_TRUE(restamp(message, Time{-3, 999999999}));
  auto back = decode_camera_info(message).value();
  EXPECT_EQ(back.header.stamp, (Time{-3, 999999999}));
  EXPECT_TRUE(same_calibration(back.calibration, some_calibration()));
  std::vector<std::byte> tiny(8);
  EXPECT_FALSE(restamp(tiny, Time{}));
}

TEST(Ros2TfMessage, MountingsRoundTripAsOneMessage) {
  SensorInfo lidar;
  lidar.frame_id = "lidar_top";
  lidar.mounting = Mounting{{0.1, 0.0, 1.8}, {0, 0, 0.38268343236508977, 0.9238795325112867}};
  SensorInfo camera;
  camera.frame_id = "camera_front_optical";
  camera.parent_frame = "camera_front";
  camera.mounting = Mounting{{0.0, 0.0, 0.0}, {-0.5, 0.5, -0.5, 0.5}};
  SensorInfo unmounted;
  unmounted.frame_id = "imu";
  EXPECT_FALSE(mounting_transform(unmounted, Time{}).has_value());

  const TransformStamped transforms[] = {*mounting_transform(lidar, Time{5, 6}),
                                         *mounting_transform(camera, Time{5, 6})};
  auto message = encode_tf_message(transforms);
  ASSERT_TRUE(message.has_value()) << message.error().message;
  auto back = decode_tf_message(*message);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  ASSERT_EQ(back->size(), 2u);
  EXPECT_EQ((*back)[0].header.frame_id, "base_link");
  EXPECT_EQ((*back)[0].child_frame_id, "lidar_top");
  EXPECT_EQ((*back)[0].transform, *lidar.mounting);
  EXPECT_EQ((*back)[1].header.frame_id, "camera_front");
  EXPECT_EQ((*back)[1].child_frame_id, "camera_front_optical");
  EXPECT_EQ((*back)[1].transform, *camera.mounting);
  EXPECT_EQ((*back)[1].header.stamp, (Time{5, 6}));
}

TEST(Ros2TfMessage, EveryTruncationAndAnAbsurdCountAreDroppedWithASentence) {
  const TransformStamped one[] = {{{Time{1, 2}, "base_link"}, "lidar_top", Mounting{}}};
  auto message = encode_tf_message(one).value();
  for (std::size_t n = 0; n < message.size(); ++n) {
    auto r = decode_tf_message(std::span(message).first(n));
    ASSERT_FALSE(r.has_value()) << n;
    EXPECT_NE(r.error().message.find("dropped a malformed tf2_msgs/msg/TFMessage"), std::string::npos);
  }
  const std::uint32_t huge = 0xffffffff;
  std::memcpy(message.data() + 4, &huge, 4);
  auto r = decode_tf_message(message);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("transforms; at most"), std::string::npos);
}

// Review L3 aside: a stamp of 10^9 nanoseconds used to be told as a field running past the end.
TEST(Ros2Messages, ANanosecondCountOfOneSecondIsToldAsABadStamp) {
  auto message = encode_camera_info({Time{1, 2}, "cam"}, some_calibration()).value();
  const std::uint32_t billion = 1'000'000'000;
  std::memcpy(message.data() + 8, &billion, 4);
  auto r = decode_camera_info(message);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("not below 1000000000"), std::string::npos) << r.error().message;
}

TEST(Ros2Graph, ParticipantEntitiesRoundTripAndBadCountsAreDropped) {
  const Gid participant{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0, 0, 1, 0xc1};
  const Gid readers[] = {{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0, 0, 2, 4}};
  const Gid writers[] = {{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0, 0, 3, 3},
                         {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0, 0, 4, 3}};
  const NodeEntities node{"/", "sim_dds_bridge", readers, writers};
  auto message = encode_participant_entities_info(participant, {&node, 1});
  // gid (16) | node count | "/" | "sim_dds_bridge" | 1 reader | 2 writers
  EXPECT_EQ(message.size(), 4u + 16 + 4 + (4 + 2 + 2) + (4 + 15 + 1) + 4 + 16 + 4 + 32);
  auto back = decode_participant_entities_info(message);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->participant, participant);
  EXPECT_EQ(back->nodes, std::vector<std::string>{"/sim_dds_bridge"});
  EXPECT_EQ(back->readers.size(), 1u);
  EXPECT_EQ(back->writers.size(), 2u);
  EXPECT_EQ(back->writers[1], writers[1]);
  for (std::size_t n = 0; n < message.size(); ++n) {
    EXPECT_FALSE(decode_participant_entities_info(std::span(message).first(n)).has_value()) << n;
  }
  const std::uint32_t huge = 0x40000000;
  std::memcpy(message.data() + message.size() - 36, &huge, 4);  // the writer count
  EXPECT_FALSE(decode_participant_entities_info(message).has_value());
}

TEST(Ros2Metadata, SchemasNameTheirNestedTypes) {
  EXPECT_NE(camera_info_schema().find("MSG: sensor_msgs/msg/RegionOfInterest\n"), std::string_view::npos);
  EXPECT_NE(camera_info_schema().find("MSG: builtin_interfaces/msg/Time\n"), std::string_view::npos);
  for (std::string_view type : {"TransformStamped", "Transform", "Vector3", "Quaternion"}) {
    EXPECT_NE(tf_message_schema().find("MSG: geometry_msgs/msg/" + std::string(type) + "\n"),
              std::string_view::npos);
  }
}

}  // namespace
