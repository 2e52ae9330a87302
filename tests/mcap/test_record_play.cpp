// SPDX-License-Identifier: Apache-2.0
// sim_record and sim_play as real processes: a camera (mcap_test_camera) and the Pandar64
// capture (sim_replay_pcap) are recorded; the file holds every frame byte for byte with its
// stamps; sim_play puts them back into SIM streams that readers cannot tell from the originals.
// Damaged recordings play as far as they are intact and say what was wrong; JPEG CompressedImage
// files without SIM metadata play too.
#include <gtest/gtest.h>
#include <turbojpeg.h>

#include "mcap_test_files.hpp"
#include "record_play_support.hpp"
#include "sim/mcap/writer.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"
#include "sim_test/process.hpp"
#include "test_frames.hpp"

namespace {

using sim::testing::FrameCollector;
using sim::testing::kCameraFrames;
using sim::testing::kHeight;
using sim::testing::kWidth;
using sim::testing::Process;
using sim::testing::Recording;
using sim::testing::unique_stream;
using sim::testing::json_number;
using sim::testing::record;

class RecordAndPlay : public ::testing::TestWithParam<std::string> {};

TEST_P(RecordAndPlay, EveryRecordedFrameComesBackByteForByteWithItsStamps) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const Recording rec = record(file.path(), GetParam(), cleanup);

  // The file: every camera frame that was not reported missed, exactly as written.
  auto recorded = sim::testing::read_recording(file.path());
  const auto& camera = recorded[rec.camera];
  const auto& lidar = recorded[rec.lidar];
  const std::uint64_t camera_missed = json_number(rec.json, rec.camera, "missed");
  ASSERT_NE(camera_missed, UINT64_MAX) << rec.json;
  EXPECT_EQ(camera.size() + camera_missed, kCameraFrames) << rec.json;
  EXPECT_EQ(json_number(rec.json, rec.camera, "frames"), camera.size());
  ASSERT_FALSE(camera.empty());
  for (const auto& m : camera) {
    const std::uint64_t index = m.sequence - 1;  // the camera's first frame is seq 1
    std::vector<std::byte> expected(std::size_t{kWidth} * 3 * kHeight);
    sim::testing::fill_test_image(expected, kWidth * 3, kHeight, index);
    EXPECT_TRUE(m.frame == expected) << "camera frame " << m.sequence << " differs";
    EXPECT_EQ(m.header_stamp_ns, sim::testing::test_image_stamp(index));
    EXPECT_EQ(static_cast<std::int64_t>(m.publish_time), sim::testing::test_image_stamp(index));
  }
  // LiDAR frames equal the frames a live reader saw with the same sequence number.
  ASSERT_FALSE(lidar.empty()) << rec.json;
  std::size_t compared = 0;
  for (const auto& m : lidar) {
    for (const auto& f : rec.live_lidar) {
      if (f.seq != m.sequence) continue;
      EXPECT_TRUE(m.frame == f.bytes) << "lidar frame " << m.sequence << " differs";
      EXPECT_EQ(m.header_stamp_ns, f.stamp_ns);
      EXPECT_EQ(static_cast<std::int64_t>(m.publish_time), f.stamp_ns);
      ++compared;
    }
  }
  EXPECT_GT(compared, 0u) << "no recorded LiDAR frame was also seen live";

  // Playback into new streams: the same bytes, stamps and layouts, in order.
  const std::string camera_out = unique_stream("cam_play");
  const std::string lidar_out = unique_stream("lidar_play");
  cleanup.names.insert(cleanup.names.end(), {camera_out, lidar_out});
  FrameCollector played_camera(camera_out);
  FrameCollector played_lidar(lidar_out);
  Process player({SIM_PLAY, file.path(), "--remap", rec.camera + "=" + camera_out, "--remap",
                  rec.lidar + "=" + lidar_out, "--wait-for-readers", "--rate", "2"});
  EXPECT_EQ(player.wait(), 0) << player.err();
  played_camera.wait_for(camera.size());
  played_lidar.wait_for(lidar.size());
  played_camera.stop();
  played_lidar.stop();

  auto check = [](const std::vector<sim::testing::Recorded>& want, FrameCollector& got_from,
                  const sim::Layout& layout, const char* what) {
    const auto got = got_from.frames();
    EXPECT_FALSE(got.empty()) << what;
    EXPECT_EQ(got.size() + got_from.skipped(), want.size()) << what;
    for (const auto& f : got) {
      ASSERT_LE(f.seq, want.size()) << what;
      const auto& m = want[f.seq - 1];  // a new stream: the k-th frame played is seq k
      EXPECT_TRUE(f.bytes == m.frame) << what << " frame " << f.seq << " differs";
      EXPECT_EQ(f.stamp_ns, m.header_stamp_ns) << what;
      EXPECT_EQ(f.layout, layout) << what << ": " << f.layout.describe();
    }
  };
  check(camera, played_camera,
        sim::Layout::of(sim::ImageLayout::packed(kWidth, kHeight, sim::PixelFormat::bgr8)), "camera");
  ASSERT_FALSE(rec.live_lidar.empty());
  check(lidar, played_lidar, rec.live_lidar.front().layout, "lidar");
}

INSTANTIATE_TEST_SUITE_P(Mcap, RecordAndPlay, ::testing::Values("zstd", "lz4", "none"));

TEST(SimPlay, PlaysTheIntactPartOfATruncatedRecordingAndSaysSo) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  const Recording rec = record(file.path(), "lz4", cleanup);
  const auto full = sim::testing::read_recording(file.path());
  const std::size_t camera_frames = full.at(rec.camera).size();

  auto bytes = sim::testing::read_bytes(file.path());
  bytes.resize(bytes.size() / 2);
  sim::testing::write_bytes(file.path(), bytes);
  const std::size_t intact = sim::testing::read_recording(file.path())[rec.camera].size();
  ASSERT_LT(intact, camera_frames);

  const std::string camera_out = unique_stream("cam_cut");
  const std::string lidar_out = unique_stream("lidar_cut");
  cleanup.names.insert(cleanup.names.end(), {camera_out, lidar_out});
  FrameCollector played(camera_out);
  Process player({SIM_PLAY, file.path(), "--remap", rec.camera + "=" + camera_out, "--remap",
                  rec.lidar + "=" + lidar_out, "--max-rate"});
  EXPECT_EQ(player.wait(), 1);
  EXPECT_NE(player.err().find("cut short"), std::string::npos) << player.err();
  played.wait_for(intact, std::chrono::seconds(5));
  played.stop();
  // Unpaced, a reader may skip frames; what it got is the intact start of the recording.
  for (const auto& f : played.frames()) EXPECT_LE(f.seq, intact);
}

TEST(SimPlay, RefusesAFileThatIsNotMcapInOneSentence) {
  sim::testing::TempFile file;
  sim::testing::write_bytes(file.path(), std::vector<std::byte>(100, std::byte{'x'}));
  const auto result = sim::testing::run({SIM_PLAY, file.path()});
  EXPECT_EQ(result.code, 1);
  EXPECT_NE(result.err.find("not an MCAP"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

TEST(SimRecord, RefusesAStreamThatDoesNotExistInOneSentence) {
  sim::testing::TempFile file;
  const auto result = sim::testing::run({SIM_RECORD, "-o", file.path(), unique_stream("absent")});
  EXPECT_EQ(result.code, 1);
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

TEST(SimRecord, AnswersAWrongCommandLineWithExitCode2) {
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "/x"}).code, 2);                        // no -o
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "-o", "x.mcap", "--all", "/x"}).code, 2);
  EXPECT_EQ(sim::testing::run({SIM_PLAY, "x.mcap", "--remap", "nonsense"}).code, 2);
  EXPECT_EQ(sim::testing::run({SIM_RECORD, "--help"}).code, 0);
  EXPECT_EQ(sim::testing::run({SIM_PLAY, "--help"}).code, 0);
}

}  // namespace

namespace {

// A 64x48 JPEG whose pixels follow from `index`.
std::vector<std::byte> make_jpeg(std::uint64_t index) {
  std::vector<unsigned char> rgb(64 * 48 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>((i / 3 + index * 40) & 0xff);
  tjhandle handle = tjInitCompress();
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  tjCompress2(handle, rgb.data(), 64, 0, 48, TJPF_RGB, &jpeg, &size, TJSAMP_420, 90, 0);
  std::vector<std::byte> out(reinterpret_cast<std::byte*>(jpeg), reinterpret_cast<std::byte*>(jpeg) + size);
  tjFree(jpeg);
  tjDestroy(handle);
  return out;
}

TEST(SimPlay, PlaysJpegCompressedImagesOfAFileWithoutSimMetadata) {
  sim::testing::TempFile file;
  sim::testing::StreamCleanup cleanup;
  std::vector<std::vector<std::byte>> jpegs;
  {
    auto writer = sim::mcap::Writer::create(file.path());
    ASSERT_TRUE(writer);
    const auto type = sim::ros2::MessageType::compressed_image;
    const auto schema = writer->add_schema(sim::ros2::ros_type_name(type), "ros2msg",
                                           sim::ros2::ros2msg_schema(type));
    const auto channel = writer->add_channel(schema, "/front_jpeg", "cdr", {{"offered_qos_profiles", ""}});
    for (std::uint64_t i = 0; i < 4; ++i) {
      jpegs.push_back(make_jpeg(i));
      const std::int64_t stamp = 1'700'000'200'000'000'000 + static_cast<std::int64_t>(i) * 50'000'000;
      auto plan = sim::ros2::plan_compressed_image("jpeg", jpegs.back().size(),
                                                   {sim::ros2::Time::from_ns(stamp), "front"});
      ASSERT_TRUE(plan);
      std::vector<std::byte> message(plan->size());
      ASSERT_EQ(plan->write(jpegs.back(), message), message.size());
      ASSERT_FALSE(writer->write({channel, static_cast<std::uint32_t>(i), static_cast<std::uint64_t>(stamp),
                                  static_cast<std::uint64_t>(stamp)}, message));
    }
    ASSERT_FALSE(writer->close());
  }
  const std::string out = unique_stream("jpeg");
  cleanup.names = {out};
  FrameCollector frames(out);
  const auto played = sim::testing::run({SIM_PLAY, file.path(), "--remap", "/front_jpeg=" + out,
                                         "--wait-for-readers"});
  EXPECT_EQ(played.code, 0) << played.err;
  frames.wait_for(4);
  frames.stop();
  const auto got = frames.frames();
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.size() + frames.skipped(), 4u);
  for (const auto& f : got) {
    ASSERT_LE(f.seq, 4u);
    EXPECT_TRUE(f.bytes == jpegs[f.seq - 1]) << "jpeg " << f.seq << " differs";
    EXPECT_EQ(f.layout.kind, sim::LayoutKind::image);
    EXPECT_EQ(f.layout.image.format, sim::PixelFormat::mjpeg);
    EXPECT_EQ(f.layout.image.width, 64u);
    EXPECT_EQ(f.layout.image.height, 48u);
    EXPECT_EQ(f.stamp_ns, 1'700'000'200'000'000'000 + static_cast<std::int64_t>(f.seq - 1) * 50'000'000);
  }
}

}  // namespace
