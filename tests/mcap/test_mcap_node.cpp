// SPDX-License-Identifier: Apache-2.0
// MCAP between SIM and Foxglove's own library (@mcap/core, npm), in Node scripts:
// - files sim_record writes, read by node/read_mcap.mjs: header and profile, the summary's
//   statistics, every channel with its schema and encoding, the message counts per channel from
//   the indexes and from a front-to-back read with every CRC checked, and the data section CRC;
// - a ROS 2 file node/write_ros2_mcap.mjs writes (no SIM metadata), played by sim_play.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "mcap_test_files.hpp"
#include "record_play_support.hpp"
#include "sim/lidar_point.hpp"
#include "sim/ros2/type_hash.hpp"

namespace {

std::string line_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) return line;
  }
  return {};
}

class ReadByMcapCore : public ::testing::TestWithParam<std::string> {};

// Messages on /diagnostics (the streams' clocks) in the file, by our reader.
std::size_t clock_messages(const std::string& path) {
  auto reader = sim::mcap::Reader::open(path);
  if (!reader) return 0;
  std::size_t n = 0;
  while (auto m = reader->next()) n += reader->channels().at(m->header.channel_id).topic == "/diagnostics";
  return n;
}

TEST_P(ReadByMcapCore, SeesEveryChannelSchemaMessageAndTheSummary) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto rec = sim::testing::record(file.path(), GetParam(), cleanup);
  auto ours = sim::testing::read_recording(file.path());
  const std::size_t camera = ours[rec.camera].size();
  const std::size_t lidar = ours[rec.lidar].size();
  ASSERT_GT(camera, 0u);
  ASSERT_GT(lidar, 0u);

  const auto node = sim::testing::run({NODE, READ_MCAP_SCRIPT, file.path()});
  ASSERT_EQ(node.code, 0) << node.err;
  EXPECT_EQ(line_starting(node.out, "header "), "header ros2 sim_record") << node.out;
  const std::string summary = line_starting(node.out, "summary ");
  // A source that reports its clock adds /diagnostics (one message per change of its record).
  const std::size_t clocks = clock_messages(file.path());
  const std::string more = clocks > 0 ? "3" : "2";
  EXPECT_NE(summary.find("messages=" + std::to_string(camera + lidar + clocks) + " "), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("schemas=" + more + " channels=" + more + " data_crc=ok"), std::string::npos)
      << summary;

  auto expect_channel = [&](const std::string& topic, const std::string& schema, std::size_t count,
                            const std::string& kind) {
    const std::string line = line_starting(node.out, "channel " + topic + " ");
    const std::string n = std::to_string(count);
    EXPECT_NE(line.find(" cdr " + schema + " ros2msg "), std::string::npos) << line;
    EXPECT_NE(line.find(" stats=" + n + " indexed=" + n + " streamed=" + n + " ordered=yes qos=yes"),
              std::string::npos)
        << line;
    EXPECT_NE(line.find(" meta:sim.kind=" + kind), std::string::npos) << line;
  };
  expect_channel(rec.camera + "/image_raw", "sensor_msgs/msg/Image", camera, "image");  // the bridge's layout
  expect_channel(rec.lidar, "sensor_msgs/msg/PointCloud2", lidar, "points");
}

INSTANTIATE_TEST_SUITE_P(Mcap, ReadByMcapCore, ::testing::Values("zstd", "lz4", "none"));

TEST(ReadByMcapCore, RejectsADamagedChunk) {
  // The reference reader must disagree with a file we damaged, or the test above proves little.
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto rec = sim::testing::record(file.path(), "none", cleanup);
  auto bytes = sim::testing::read_bytes(file.path());
  bytes[bytes.size() / 3] ^= std::byte{0x40};  // inside the data section, in some chunk
  sim::testing::write_bytes(file.path(), bytes);
  const auto node = sim::testing::run({NODE, READ_MCAP_SCRIPT, file.path()});
  EXPECT_EQ(node.code, 1) << node.out;
  EXPECT_NE(node.err.find("CRC"), std::string::npos) << node.err;
}

}  // namespace

namespace {

// A ROS 2 recording made outside SIM (node/write_ros2_mcap.mjs: @mcap/core's writer and
// Foxglove's CDR serializer) plays into SIM streams with every value where it belongs.
TEST(PlayForeignRecording, PutsEveryPointAndPixelOfAnotherWritersFileIntoSim) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto written = sim::testing::run({NODE, WRITE_ROS2_SCRIPT, file.path()});
  ASSERT_EQ(written.code, 0) << written.err;
  const std::string cloud_out = sim::testing::unique_stream("ext_cloud");
  const std::string image_out = sim::testing::unique_stream("ext_image");
  cleanup.names = {cloud_out, image_out};
  sim::testing::FrameCollector clouds(cloud_out);
  sim::testing::FrameCollector images(image_out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/ext/cloud=" + cloud_out,
                                         "--remap", "/ext/image=" + image_out, "--wait-for-readers",
                                         "--rate", "20"});
  EXPECT_EQ(played.code, 0) << played.err;
  clouds.wait_for(5);
  images.wait_for(5);
  clouds.stop();
  images.stop();

  const auto cloud_frames = clouds.frames();
  ASSERT_FALSE(cloud_frames.empty());
  EXPECT_EQ(cloud_frames.size() + clouds.skipped(), 5u);
  for (const auto& f : cloud_frames) {
    const std::uint64_t m = f.seq - 1;
    EXPECT_EQ(f.stamp_ns, (1700000100 + static_cast<std::int64_t>(m)) * 1'000'000'000 + 5000);
    ASSERT_EQ(f.layout.kind, sim::LayoutKind::points);
    EXPECT_EQ(f.layout.points.type, sim::PointType::lidar_point);  // it has rings
    ASSERT_EQ(f.bytes.size(), 100 * sizeof(sim::LidarPoint));
    std::vector<sim::LidarPoint> points(100);
    std::memcpy(points.data(), f.bytes.data(), f.bytes.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      EXPECT_EQ(points[k].x, static_cast<float>(m) + static_cast<float>(k) / 2);
      EXPECT_EQ(points[k].y, -static_cast<float>(k));
      EXPECT_EQ(points[k].z, static_cast<float>(k) / 4);
      EXPECT_EQ(points[k].intensity, static_cast<float>(k));
      EXPECT_EQ(points[k].ring, k % 64);
    }
  }
  const auto image_frames = images.frames();
  ASSERT_FALSE(image_frames.empty());
  EXPECT_EQ(image_frames.size() + images.skipped(), 5u);
  for (const auto& f : image_frames) {
    const std::uint64_t m = f.seq - 1;
    auto layout = sim::ImageLayout::packed(4, 3, sim::PixelFormat::rgb8);
    layout.stride = 16;  // the row padding is kept
    EXPECT_EQ(f.layout, sim::Layout::of(layout)) << f.layout.describe();
    ASSERT_EQ(f.bytes.size(), 48u);
    for (std::size_t j = 0; j < f.bytes.size(); ++j) {
      EXPECT_EQ(static_cast<std::uint8_t>(f.bytes[j]), (3 * m + j) % 256);
    }
  }
}

}  // namespace

namespace {

// Issue 21: what sim_record writes about the sensors, read by Foxglove's own libraries
// (node/read_sensor_mcap.mjs), and what sim_play restores from it and from a rosbag2-style file
// (node/write_rosbag2_sensor.mjs, written without any SIM code).

// Lines of `out` that start with `prefix`.
std::vector<std::string> lines_starting(const std::string& out, const std::string& prefix) {
  std::vector<std::string> lines;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) lines.push_back(line);
  }
  return lines;
}

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The stream's description as sim_play left it (--keep-streams: the region stays after it ends).
std::optional<sim::SensorInfo> sensor_of(const std::string& stream) {
  auto status = sim::inspect(stream);
  if (!status) return std::nullopt;
  return status->sensor;
}

TEST(SensorMetadataInMcap, FoxgloveReadsTheCalibrationBesideEveryImageLatchedTransformsAndTypeHashes) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const std::string camera = sim::testing::unique_stream("calcam");
  cleanup.names = {camera};
  sim::testing::Process source({MCAP_TEST_CAMERA, "--stream", camera, "--width", "64", "--height", "48",
                                "--frames", "12", "--fps", "30", "--wait-for-reader", "--calibrated"});
  ASSERT_TRUE(source.wait_for_line("ready"));
  sim::testing::Process recorder({SIM_RECORD, "-o", file.path(), camera, "--quiet"});
  ASSERT_TRUE(recorder.wait_for_line("recording")) << recorder.err();
  EXPECT_EQ(source.wait(), 0) << source.err();
  recorder.signal(SIGINT);  // a stopped sim_record still takes the newest frame
  ASSERT_EQ(recorder.wait(), 0) << recorder.err();

  const auto node = sim::testing::run({NODE, READ_SENSOR_SCRIPT, file.path()});
  ASSERT_EQ(node.code, 0) << node.err;
  // Every channel: rosbag2's topic_type_hash, RIHS01 of its type.
  const auto channels = lines_starting(node.out, "channel ");
  ASSERT_EQ(channels.size(), 3u) << node.out;
  for (const auto& line : channels) {
    const auto w = words(line);
    ASSERT_EQ(w.size(), 5u) << line;
    EXPECT_TRUE(std::regex_match(w[3], std::regex("hash=RIHS01_[0-9a-f]{64}"))) << line;
    EXPECT_EQ(w[3], "hash=" + std::string(sim::ros2::rihs01_type_hash(w[2]))) << line;
  }
  // The transforms: latched (transient local = 1 in rosbag2's offered QoS), with the mounting.
  EXPECT_EQ(line_starting(node.out, "channel /tf_static "),
            "channel /tf_static tf2_msgs/msg/TFMessage hash=" +
                std::string(sim::ros2::rihs01_type_hash("tf2_msgs/msg/TFMessage")) + " durability=1");
  EXPECT_EQ(line_starting(node.out, "tf "), "tf base_link test_camera_optical t=1.25,-0.5,1.75 r=0,0,0.6,0.8");
  // One CameraInfo beside each image: the sibling topic, the identical stamp and frame id.
  const auto images = lines_starting(node.out, "image ");
  const auto infos = lines_starting(node.out, "camera_info ");
  ASSERT_FALSE(images.empty()) << node.out;
  EXPECT_EQ(images.size(), infos.size());
  std::map<std::string, std::vector<std::string>> info_by_stamp;
  for (const auto& line : infos) info_by_stamp[words(line)[2]] = words(line);
  for (const auto& line : images) {
    const auto w = words(line);
    EXPECT_EQ(w[1], camera + "/image_raw");
    EXPECT_EQ(w[3], "test_camera_optical");
    ASSERT_TRUE(info_by_stamp.count(w[2])) << "no calibration with the stamp of " << line;
    const auto& info = info_by_stamp[w[2]];
    EXPECT_EQ(info[1], camera + "/camera_info");
    EXPECT_EQ(info[3], w[3]);
    EXPECT_EQ(info[4], "64x48");
    EXPECT_EQ(info[5], "plumb_bob");
    EXPECT_EQ(info[6], "d=-0.25,0.125,0.001,-0.002,0.03");
    EXPECT_EQ(info[7], "k=410.5,0,32.5,0,411.5,23.5,0,0,1");
    EXPECT_EQ(info[8], "p=405.25,0,32,0,0,406.75,24,0,0,0,1,0");
  }

  // sim_play gives the stream its description back.
  const std::string out = sim::testing::unique_stream("calplay");
  cleanup.names.push_back(out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", camera + "=" + out, "--max-rate",
                                         "--keep-streams"});
  EXPECT_EQ(played.code, 0) << played.err;
  const auto sensor = sensor_of(out);
  ASSERT_TRUE(sensor) << played.err;
  const auto want = sim::testing::test_camera_sensor(64, 48);
  EXPECT_EQ(sensor->frame_id, want.frame_id);
  EXPECT_EQ(sensor->parent_frame, want.parent_frame);
  EXPECT_EQ(sensor->mounting, want.mounting);
  ASSERT_TRUE(sensor->calibration);
  EXPECT_EQ(sensor->calibration->k, want.calibration->k);
  EXPECT_EQ(sensor->calibration->d, want.calibration->d);
  EXPECT_EQ(sensor->calibration->p, want.calibration->p);
  EXPECT_EQ(sensor->calibration->width, 64u);
}

// Issue 30: each change of a stream's clock is one DiagnosticArray on /diagnostics, which
// Foxglove's libraries read, and sim_play gives the played stream the clock record back.
TEST(ClockInMcap, FoxgloveReadsEachClockChangeOnDiagnosticsAndSimPlayRestoresTheRecord) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const std::string camera = sim::testing::unique_stream("clockcam");
  cleanup.names = {camera};
  sim::testing::Process source({MCAP_TEST_CAMERA, "--stream", camera, "--width", "64", "--height", "48",
                                "--frames", "12", "--fps", "30", "--wait-for-reader", "--clock"});
  ASSERT_TRUE(source.wait_for_line("ready"));
  sim::testing::Process recorder({SIM_RECORD, "-o", file.path(), camera, "--quiet"});
  ASSERT_TRUE(recorder.wait_for_line("recording")) << recorder.err();
  EXPECT_EQ(source.wait(), 0) << source.err();
  recorder.signal(SIGINT);  // a stopped sim_record still takes the newest frame
  ASSERT_EQ(recorder.wait(), 0) << recorder.err();

  const auto node = sim::testing::run({NODE, READ_SENSOR_SCRIPT, file.path()});
  ASSERT_EQ(node.code, 0) << node.err;
  EXPECT_EQ(line_starting(node.out, "channel /diagnostics "),
            "channel /diagnostics diagnostic_msgs/msg/DiagnosticArray hash=" +
                std::string(sim::ros2::rihs01_type_hash("diagnostic_msgs/msg/DiagnosticArray")) +
                " durability=2");
  // The error first, then the fixed clock: one status each, in the order they happened.
  const auto statuses = lines_starting(node.out, "diagnostic /diagnostics ");
  ASSERT_EQ(statuses.size(), 2u) << node.out;
  const std::string name = "\"sim: " + camera + " clock\"";
  EXPECT_NE(statuses[0].find(" level=2 hw=" + camera + " clock_source=ptp sync_state=locked "
                             "offset_from_master_ns=-42 grandmaster_id=00a069.fffe.0b552d "
                             "offset_to_host_ns=37000012000 "),
            std::string::npos) << statuses[0];
  EXPECT_NE(statuses[0].find(name + " \"" + sim::testing::test_camera_clock(false).problem + "\""),
            std::string::npos) << statuses[0];
  EXPECT_NE(statuses[1].find(" level=0 "), std::string::npos) << statuses[1];
  EXPECT_NE(statuses[1].find(" tai_correction_ns=37000000000 stamps=sensor_tai_corrected "),
            std::string::npos) << statuses[1];

  // sim_play: the played stream reports the clock as it was recorded last.
  const std::string out = sim::testing::unique_stream("clockplay");
  cleanup.names.push_back(out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", camera + "=" + out, "--max-rate",
                                         "--keep-streams"});
  EXPECT_EQ(played.code, 0) << played.err;
  auto reader = sim::Reader::open(out);
  ASSERT_TRUE(reader) << reader.error().message << "\n" << played.err;
  auto clock = reader->clock();
  ASSERT_TRUE(clock) << clock.error().message;
  ASSERT_TRUE(clock->has_value()) << played.err;
  EXPECT_TRUE(**clock == sim::testing::test_camera_clock(true))
      << sim::summary(**clock) << "\n" << played.err;
}

TEST(SensorMetadataInMcap, ARosbag2RecordingPlaysBackWithItsCalibrationAndMounting) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto written = sim::testing::run({NODE, WRITE_ROSBAG2_SENSOR_SCRIPT, file.path()});
  ASSERT_EQ(written.code, 0) << written.err;
  const std::string out = sim::testing::unique_stream("rosbag2cam");
  cleanup.names = {out};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/cam/front/image_raw=" + out,
                                         "--max-rate", "--keep-streams"});
  EXPECT_EQ(played.code, 0) << played.err;  // camera_info and /tf_static are metadata, not refused topics
  EXPECT_NE(played.err.find(out + " 5"), std::string::npos) << played.err;
  const auto sensor = sensor_of(out);
  ASSERT_TRUE(sensor) << played.err;
  EXPECT_EQ(sensor->frame_id, "cam_front_optical");
  EXPECT_EQ(sensor->parent_frame, "base_link");
  EXPECT_EQ(sensor->mounting, (sim::Mounting{{1.5, 0.25, 2.0}, {0.0, 0.0, 0.6, 0.8}}));
  ASSERT_TRUE(sensor->calibration);
  EXPECT_EQ(sensor->calibration->width, 4u);
  EXPECT_EQ(sensor->calibration->height, 3u);
  EXPECT_EQ(sensor->calibration->distortion_model, "plumb_bob");
  EXPECT_EQ(sensor->calibration->d, (std::vector<double>{-0.2, 0.1, 0, 0, 0.01}));
  EXPECT_EQ(sensor->calibration->k, (std::array<double, 9>{500, 0, 2, 0, 501, 1.5, 0, 0, 1}));
  EXPECT_EQ(sensor->calibration->p, (std::array<double, 12>{499, 0, 2, 0, 0, 498, 1.5, 0, 0, 0, 1, 0}));
}

// Review turn 4 M2, M3, M5: a RealSense-like recording without calibration (K all zero, no
// distortion_model) whose optical frame hangs off base_link through camera_link and
// camera_color_frame, one rotation typed with four decimals: the stream gets the whole chain
// composed as its mounting under base_link, and no calibration.
TEST(SensorMetadataInMcap, AnUncalibratedRigPlaysBackWithItsChainOfMountingsComposed) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const auto written = sim::testing::run({NODE, WRITE_ROSBAG2_SENSOR_SCRIPT, file.path(), "uncalibrated-rig"});
  ASSERT_EQ(written.code, 0) << written.err;
  const std::string out = sim::testing::unique_stream("rosbag2rig");
  cleanup.names = {out};
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/cam/front/image_raw=" + out,
                                         "--max-rate", "--keep-streams"});
  EXPECT_EQ(played.code, 0) << played.err;
  const auto sensor = sensor_of(out);
  ASSERT_TRUE(sensor) << "no description: " << played.err;
  EXPECT_EQ(sensor->frame_id, "camera_color_optical_frame");
  EXPECT_EQ(sensor->parent_frame, "base_link") << "one hop of the chain: " << played.err;
  EXPECT_FALSE(sensor->calibration) << "an all-zero K is no calibration";
  ASSERT_TRUE(sensor->mounting) << played.err;
  // camera_link turned 90 degrees about z carries camera_color_frame 15 mm along its y: -x of base_link.
  const auto& t = sensor->mounting->translation;
  EXPECT_NEAR(t[0], 0.985, 1e-4);
  EXPECT_NEAR(t[1], 0.0, 1e-4);
  EXPECT_NEAR(t[2], 0.5, 1e-12);
  // (0, 0, s, s) * (-0.5, 0.5, -0.5, 0.5) = (-s, 0, 0, s), s = sqrt(1/2), stored as a unit quaternion.
  const auto& q = sensor->mounting->rotation;
  const double s = std::sqrt(0.5);
  EXPECT_NEAR(q[0], -s, 1e-12);
  EXPECT_NEAR(q[1], 0.0, 1e-12);
  EXPECT_NEAR(q[2], 0.0, 1e-12);
  EXPECT_NEAR(q[3], s, 1e-12);
}

}  // namespace
