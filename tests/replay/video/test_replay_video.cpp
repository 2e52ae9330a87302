// SPDX-License-Identifier: Apache-2.0
// sim_replay_video in its own process, read back here: fixtures are written by this test with
// cv::VideoWriter (FFV1 for lossless content checks, MJPG in AVI) and cv::imwrite (PNG folder).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "sim/sim.hpp"

namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

constexpr int kWidth = 96;
constexpr int kHeight = 64;

// Frame k: a gradient plus a bright bar whose position encodes k, so frames can be told apart.
cv::Mat make_frame(int k) {
  cv::Mat frame(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      frame.at<cv::Vec3b>(y, x) = {static_cast<uchar>(x * 2), static_cast<uchar>(y * 3),
                                   static_cast<uchar>((k * 10) % 256)};
    }
  }
  frame.colRange(k * 4 % kWidth, k * 4 % kWidth + 4).setTo(cv::Scalar(255, 255, 255));
  return frame;
}

class ReplayVideo : public ::testing::Test {
 protected:
  ReplayVideo() {
    static int counter = 0;
    const std::string id = std::to_string(getpid()) + "_" + std::to_string(counter++);
    dir = fs::temp_directory_path() / ("test_replay_video_" + id);
    fs::create_directories(dir);
    stream = "/test_replay_video_" + id;
  }
  ~ReplayVideo() override {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    (void)sim::destroy(stream, true);
    fs::remove_all(dir);
  }

  std::string write_video(const std::string& name, int fourcc, int frames) {
    const std::string path = (dir / name).string();
    cv::VideoWriter writer(path, cv::CAP_FFMPEG, fourcc, 25.0, cv::Size(kWidth, kHeight));
    EXPECT_TRUE(writer.isOpened()) << path;
    for (int k = 0; k < frames; ++k) writer.write(make_frame(k));
    writer.release();
    return path;
  }

  void spawn(std::vector<std::string> args) {
    args.insert(args.begin(), SIM_REPLAY_VIDEO_TOOL);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    log = (dir / "stderr.txt").string();
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
    ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
  }

  // Exit code of the tool, or -1 if it had to be killed after `limit`.
  int wait_exit(std::chrono::seconds limit = 30s) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    int status = 0;
    while (waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        pid = -1;
        return -1;
      }
      std::this_thread::sleep_for(10ms);
    }
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  int run(std::vector<std::string> args) {
    spawn(std::move(args));
    return wait_exit();
  }

  std::string output() const {
    std::ifstream file(log);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }

  std::optional<sim::Reader> open_reader() {
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (std::chrono::steady_clock::now() < deadline) {
      auto reader = sim::Reader::open(stream);
      if (reader) return std::move(reader.value());
      std::this_thread::sleep_for(5ms);
    }
    return std::nullopt;
  }

  // Reads frames until the tool is gone; returns them as BGR/grey matrices.
  std::vector<cv::Mat> collect(sim::Reader& reader, std::size_t at_most = 1000) {
    std::vector<cv::Mat> frames;
    std::vector<std::byte> buffer(reader.capacity());
    sim::FrameInfo info;
    std::uint64_t last_seq = 0;
    while (frames.size() < at_most) {
      const auto status = reader.read_next(buffer, info, 200ms);
      if (status == sim::ReadStatus::writer_gone) break;
      if (status != sim::ReadStatus::new_frame) continue;
      EXPECT_GT(info.seq, last_seq);
      last_seq = info.seq;
      // When the frame came off the file, beside its stamp: consumers measure the replay's delay.
      EXPECT_GT(info.receive_ns, 0);
      EXPECT_LE(info.receive_ns, info.stamp_ns);
      const auto& image = info.layout.image;
      const int type = image.channels == 3 ? CV_8UC3 : CV_8UC1;
      frames.push_back(
          cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                  buffer.data(), image.stride).clone());
    }
    return frames;
  }

  fs::path dir;
  std::string stream;
  std::string log;
  pid_t pid = -1;
};

// Which generated frame this is, or -1 if it is none of them exactly.
int identify(const cv::Mat& frame, int count) {
  for (int k = 0; k < count; ++k) {
    if (cv::norm(frame, make_frame(k), cv::NORM_INF) == 0) return k;
  }
  return -1;
}

TEST_F(ReplayVideo, LosslessFileArrivesPixelExactInOrder) {
  const std::string path = write_video("clip.mkv", cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 20);
  spawn({path, "--stream", stream, "--fps", "40"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  EXPECT_EQ(reader->layout().image.width, static_cast<std::uint32_t>(kWidth));
  EXPECT_EQ(reader->layout().image.format, sim::PixelFormat::bgr8);
  const auto frames = collect(*reader);
  EXPECT_EQ(wait_exit(), 0) << output();
  ASSERT_GE(frames.size(), 5u) << output();
  int last = -1;
  for (const auto& frame : frames) {
    const int k = identify(frame, 20);
    ASSERT_GE(k, 0) << "a published frame is not one of the file's frames";
    EXPECT_GT(k, last);
    last = k;
  }
  EXPECT_NE(output().find("published 20 frames"), std::string::npos) << output();
}

TEST_F(ReplayVideo, MjpegAviLoopsInMonoUntilStopped) {
  const std::string path = write_video("clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 6);
  spawn({path, "--stream", stream, "--fps", "30", "--rate", "4", "--loop", "--output", "mono8"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  EXPECT_EQ(reader->layout().image.format, sim::PixelFormat::mono8);
  EXPECT_EQ(reader->layout().image.stride, static_cast<std::uint32_t>(kWidth));
  // More frames than the file holds: it looped.
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (info.seq <= 14 && std::chrono::steady_clock::now() < deadline) {
    (void)reader->read_next(buffer, info, 200ms);
  }
  EXPECT_GT(info.seq, 14u);
  // MJPEG is lossy: the grey frame is near OpenCV's grey of one of the sources.
  const cv::Mat grey(kHeight, kWidth, CV_8UC1, buffer.data());
  EXPECT_GT(cv::mean(grey)[0], 40.0);
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();
  // MJPEG files take the camera's JPEG path (libjpeg-turbo into the slot), not OpenCV's decode.
  EXPECT_NE(output().find("MJPEG"), std::string::npos) << output();
}

TEST_F(ReplayVideo, FolderOfImagesInNameOrder) {
  fs::create_directories(dir / "frames");
  for (int k = 0; k < 4; ++k) {
    cv::imwrite((dir / "frames" / ("frame_" + std::to_string(k) + ".png")).string(), make_frame(k));
  }
  std::ofstream(dir / "frames" / "notes.txt") << "not an image";
  spawn({(dir / "frames").string(), "--stream", stream, "--fps", "10"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  const auto frames = collect(*reader);
  EXPECT_EQ(wait_exit(), 0) << output();
  ASSERT_GE(frames.size(), 2u);
  int last = -1;
  for (const auto& frame : frames) {
    const int k = identify(frame, 4);
    ASSERT_GE(k, 0);
    EXPECT_GT(k, last);
    last = k;
  }
  EXPECT_EQ(last, 3);
}

TEST_F(ReplayVideo, BadInputFailsWithOneSentence) {
  EXPECT_EQ(run({(dir / "missing.avi").string(), "--stream", stream}), 1);
  EXPECT_NE(output().find("no file or folder at"), std::string::npos) << output();

  std::ofstream(dir / "fake.avi") << "this is not a video at all";
  EXPECT_EQ(run({(dir / "fake.avi").string(), "--stream", stream}), 1);
  EXPECT_NE(output().find("sim_replay_video: "), std::string::npos) << output();

  fs::create_directories(dir / "empty");
  EXPECT_EQ(run({(dir / "empty").string(), "--stream", stream}), 1);
  EXPECT_NE(output().find("holds no images"), std::string::npos) << output();

  const std::string path = write_video("ok.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 2);
  EXPECT_EQ(run({path, "--stream", stream, "--rate", "0"}), 2);
  EXPECT_EQ(run({path, "--stream", "no-slash"}), 2);  // a wrong command line, refused first
  EXPECT_NE(output().find("sim_replay_video: "), std::string::npos);
  EXPECT_EQ(run({"--help"}), 0);
  EXPECT_FALSE(sim::Reader::open(stream));  // nothing was published by any failed run
}

}  // namespace

namespace {

// A camera_calibration_parsers file as ROS's cameracalibrator writes it, written here by hand
// (not by SIM's writer) for a camera of `width` × `height`.
std::string calibration_yaml(int width, int height, const std::string& fx = "90.5") {
  return "image_width: " + std::to_string(width) + "\nimage_height: " + std::to_string(height) +
         "\ncamera_name: replayed\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [" + fx +
         ", 0, 48.25, 0, 91, 32.5, 0, 0, 1]\ndistortion_model: plumb_bob\n"
         "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [-0.1, 0.01, 0, 0, 0]\n"
         "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
         "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [" + fx +
         ", 0, 48.25, 0, 0, 91, 32.5, 0, 0, 0, 1, 0]\n";
}

}  // namespace

TEST_F(ReplayVideo, TheStreamCarriesTheCalibrationFileAndMountingGiven) {
  const std::string video = write_video("clip.mkv", cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 5);
  const std::string yaml = (dir / "front.yaml").string();
  std::ofstream(yaml) << calibration_yaml(kWidth, kHeight);
  spawn({video, "--stream", stream, "--loop", "-q", "--camera-info", "file://" + yaml,
         "--frame-id", "camera_front_optical", "--z", "1.4", "--roll", "-1.5707963"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  auto info = reader->sensor_info();
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  const sim::SensorInfo& s = **info;
  EXPECT_EQ(s.frame_id, "camera_front_optical");
  EXPECT_EQ(s.parent_frame, "base_link");
  ASSERT_TRUE(s.mounting.has_value());
  EXPECT_EQ(s.mounting->translation[2], 1.4);
  ASSERT_TRUE(s.calibration.has_value());
  EXPECT_EQ(s.calibration->width, static_cast<std::uint32_t>(kWidth));
  EXPECT_EQ(s.calibration->camera_name, "replayed");
  EXPECT_EQ(s.calibration->k[0], 90.5);
  EXPECT_EQ(s.calibration->k[5], 32.5);
  EXPECT_EQ(s.calibration->d[0], -0.1);
  EXPECT_EQ(s.calibration_source, "file://" + yaml);
  EXPECT_EQ(s.time_base, sim::TimeBase::host);
  EXPECT_EQ(s.time_sync, "replayed, stamped with this host's clock when published");
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();
}

TEST_F(ReplayVideo, ABadCalibrationIsOneSentenceExitTwoAndNoStream) {
  const std::string video = write_video("clip.mkv", cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 3);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {calibration_yaml(640, 480), "640x480"},            // another camera mode
      {calibration_yaml(kWidth, kHeight, ".nan"), "finite"},  // a number that is not one
      {"image_width: [96\n", "not valid YAML"},            // malformed
      {calibration_yaml(kWidth, kHeight).substr(0, calibration_yaml(kWidth, kHeight).find("rect")),
       "has no 'rectification_matrix'"},  // cut short
  };
  int index = 0;
  for (const auto& [text, expected] : bad) {
    const std::string yaml = (dir / ("bad" + std::to_string(index++) + ".yaml")).string();
    std::ofstream(yaml) << text;
    EXPECT_EQ(run({video, "--stream", stream, "-q", "--camera-info", yaml}), 2) << output();
    const std::string message = output();
    EXPECT_EQ(message.rfind("sim_replay_video: ", 0), 0u) << message;
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), message.size() - 1) << "one line: " << message;
    auto reader = sim::Reader::open(stream);
    ASSERT_FALSE(reader) << "a stream was created for " << expected;
  }
  EXPECT_EQ(run({video, "--stream", stream, "-q", "--frame-id", "camera front"}), 2) << output();
  EXPECT_FALSE(sim::Reader::open(stream));
}
