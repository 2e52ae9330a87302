// SPDX-License-Identifier: Apache-2.0
// sim_replay_video: replays a video file or a folder of images into a SIM image stream at the
// recorded rate, through the decoder the live camera drivers use.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "sim/camera/decoder.hpp"
#include "sim/camera/image_format.hpp"
#include "sim/clock.hpp"
#include "sim/os.hpp"
#include "sim/writer.hpp"
#include "video_source.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

// Sleeps until an absolute CLOCK_MONOTONIC time, so per-frame work never accumulates as drift
// (relative sleeps run ~20 % slow at high rates). False if interrupted by a stop signal.
bool sleep_until(std::int64_t deadline_ns) {
  timespec ts{};
  ts.tv_sec = deadline_ns / 1'000'000'000;
  ts.tv_nsec = deadline_ns % 1'000'000'000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    if (g_stop.load()) return false;
  }
  return true;
}

// One sentence on stderr; returns the runtime-failure exit code.
int fail(const std::string& message) {
  std::fprintf(stderr, "sim_replay_video: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sim;
  CLI::App app{"Replays a video file (anything FFmpeg decodes) or a folder of images into a SIM "
               "image stream at the recorded rate."};
  std::string path;
  std::string stream = "/camera_front";
  std::string output_text = "bgr8";
  double fps = 0;
  double rate = 1.0;
  bool loop = false;
  bool checksum = false;
  bool quiet = false;
  int cpu = -1;
  int rt_priority = 0;
  app.add_option("source", path, "Video file, or folder of images played in name order")
      ->required();
  app.add_option("--stream", stream, "SIM stream name");
  app.add_option("--fps", fps, "Frame rate (default: the file's own, 30 for a folder)")
      ->check(CLI::Range(0.001, 10000.0));
  app.add_option("--rate", rate, "Speed factor: 2 plays twice as fast")
      ->check(CLI::Range(0.001, 1000.0));
  app.add_flag("--loop", loop, "Start again at the end, until stopped");
  app.add_option("--output", output_text, "Published format: bgr8, rgb8 or mono8")
      ->check(CLI::IsMember({"bgr8", "rgb8", "mono8"}));
  app.add_flag("--checksum", checksum, "Publish an XXH3 checksum with every frame");
  app.add_option("--cpu", cpu, "Pin the replay thread to this CPU");
  app.add_option("--rt-priority", rt_priority, "Run under SCHED_FIFO at this priority (1-99)")
      ->check(CLI::Range(1, 99));
  app.add_flag("-q,--quiet", quiet, "No progress line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const auto output = *camera::parse_output_format(output_text);

  ThreadPlacement placement;
  if (cpu >= 0) placement.cpu = cpu;
  if (rt_priority > 0) placement.rt_priority = rt_priority;
  if (auto placed = apply_thread_placement(placement); !placed) return fail(placed.error().message);

  auto source = replay::VideoSource::open(path);
  if (!source) return fail(source.error().message);
  auto& video = *source.value();

  cv::Mat frame;
  if (!video.next(frame)) return fail(path + " has no frame that can be decoded");
  const bool jpeg = video.jpeg_frames();
  const auto width = static_cast<std::uint32_t>(jpeg ? video.width() : frame.cols);
  const auto height = static_cast<std::uint32_t>(jpeg ? video.height() : frame.rows);
  if (!jpeg && frame.type() != CV_8UC3) return fail(path + " does not decode to 8-bit colour frames");

  if (fps <= 0) fps = video.fps();
  if (!(fps > 0 && fps <= 10000)) fps = 30;  // folders and files without a usable rate
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / (fps * rate)));

  // The decoder the live cameras use: JPEG bytes like a UVC camera's, or BGR pixels.
  const ImageLayout input =
      jpeg ? camera::make_layout(width, height, PixelFormat::mjpeg)
           : camera::make_layout(width, height, PixelFormat::bgr8,
                                 static_cast<std::uint32_t>(frame.step[0]));
  auto decoder = camera::FrameDecoder::create(input, output);
  if (!decoder) return fail(decoder.error().message);
  StreamSpec spec;
  spec.name = stream;
  spec.layout = Layout::of(decoder->output_layout());
  spec.checksum = checksum;
  // Before the stream exists: a reader may see it and stop us at once.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  auto writer = Writer::create(spec);
  if (!writer) return fail(writer.error().message);

  const bool terminal = !quiet && isatty(STDERR_FILENO) != 0;
  std::fprintf(stderr, "sim_replay_video: %s, %ux%u%s at %.4g fps x %.3g -> %s (%s)%s\n",
               video.describe().c_str(), width, height, jpeg ? " MJPEG" : "", fps, rate,
               stream.c_str(),
               Layout::of(decoder->output_layout()).describe().c_str(), loop ? ", looping" : "");

  const long long total = video.frame_count();
  long long published = 0;
  long long skipped = 0;
  long long in_pass = 0;
  int pass = 1;
  std::int64_t start = monotonic_ns();
  std::int64_t last_progress = start;
  long long index = 0;  // position on the schedule, across loops
  bool have_frame = true;
  while (have_frame && !g_stop.load()) {
    // Decode into the slot before the deadline, publish at the deadline: decode time does not
    // delay the frame.
    sim::Loan loan = writer->loan();
    // Pixel frames must keep the first frame's size; JPEG frames are checked by the decoder.
    const bool fits = frame.isContinuous() &&
                      (jpeg || (frame.cols == static_cast<int>(width) &&
                                frame.rows == static_cast<int>(height) && frame.type() == CV_8UC3));
    camera::DecodeResult decoded;
    if (fits) {
      decoded = decoder->decode(
          std::span<const std::byte>(reinterpret_cast<const std::byte*>(frame.data),
                                     frame.total() * frame.elemSize()),
          loan.bytes());
    }
    std::int64_t deadline = start + index * period_ns;
    const std::int64_t now = monotonic_ns();
    if (now - deadline > 1'000'000'000) {
      // More than a second behind (a stopped process, a slow disk): start a new schedule here
      // instead of publishing a burst of stale frames.
      start = now - index * period_ns;
      deadline = now;
    }
    if (!sleep_until(deadline)) break;
    if (fits && decoded.status == camera::DecodeStatus::ok &&
        std::move(loan).commit(decoded.size, realtime_ns()) == WriteStatus::ok) {
      ++published;
    } else {
      ++skipped;  // a corrupt frame, or one of another size: never published
    }
    ++index;
    ++in_pass;

    if (terminal && monotonic_ns() - last_progress > 500'000'000) {
      last_progress = monotonic_ns();
      if (total > 0) {
        std::fprintf(stderr, "\r\033[Kframe %lld/%lld (%.0f%%)%s%s", in_pass, total,
                     100.0 * static_cast<double>(in_pass) / static_cast<double>(total),
                     loop ? ", pass " : "", loop ? std::to_string(pass).c_str() : "");
      } else {
        std::fprintf(stderr, "\r\033[Kframe %lld", in_pass);
      }
    }

    have_frame = video.next(frame);
    if (!have_frame && loop && !g_stop.load()) {
      if (!video.rewind()) return fail("cannot reopen " + path + " to loop it");
      ++pass;
      in_pass = 0;
      have_frame = video.next(frame);
    }
  }
  if (terminal) std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "sim_replay_video: published %lld frames%s\n", published,
               skipped > 0 ? (", skipped " + std::to_string(skipped) + " corrupt or misfit").c_str()
                           : "");
  return 0;
}
