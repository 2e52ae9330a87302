// SPDX-License-Identifier: Apache-2.0
// sim_replay_video: replays a video file or a folder of images into a SIM image stream at the
// recorded rate, through the decoder the live camera drivers use.
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "sim/apps/command_line.hpp"
#include "sim/apps/pacer.hpp"
#include "sim/apps/sensor_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/clock.hpp"
#include "sim/imaging/decoder.hpp"
#include "sim/imaging/image_format.hpp"
#include "sim/writer.hpp"
#include "video_source.hpp"

namespace {

using namespace sim;

struct Options {
  std::string path;
  std::string stream = "/camera_front";
  std::string output_text = "bgr8";
  double fps = 0;
  double rate = 1.0;
  bool loop = false;
  bool checksum = false;
  bool quiet = false;
  ThreadPlacement placement;
  apps::SensorOptions sensor;
};

void add_options(apps::CommandLine& cli, Options& o) {
  cli.add_option("source", o.path, "video file, or folder of images played in name order")
      .required();
  cli.add_stream("--stream", o.stream, "SIM stream name");
  cli.add_option("--fps", o.fps, "frame rate (0: the file's own, 30 for a folder)")
      .in_range(0.0, 10000.0);
  cli.add_option("--rate", o.rate, "speed factor: 2 plays twice as fast")
      .in_range(0.001, 1000.0);
  cli.add_flag("--loop", o.loop, "start again at the end, until stopped");
  cli.add_option("--output", o.output_text, "published format: bgr8, rgb8 or mono8")
      .one_of({"bgr8", "rgb8", "mono8"});
  cli.add_flag("--checksum", o.checksum, "publish an XXH3 checksum with every frame");
  apps::add_sensor_options(cli, o.sensor, apps::SensorKind::camera);
  cli.add_placement(o.placement);
  cli.add_flag("-q,--quiet", o.quiet, "no progress line and no summary");
}

// The sensor the options describe, stamped as a replay is: with this host's clock.
Expected<SensorInfo> replayed_sensor(const Options& o) {
  auto described = apps::sensor_info_from(o.sensor, o.stream);
  if (!described) return described;
  apps::describe_stamped_on_publish(*described);
  return described;
}

// What the first frame says about every frame: its size, and whether the source gives JPEG bytes
// (like a UVC camera's) or BGR pixels.
struct Input {
  bool jpeg = false;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  ImageLayout layout;  // what the decoder takes
};

Input input_of(const replay::VideoSource& video, const cv::Mat& first) {
  Input input;
  input.jpeg = video.jpeg_frames();
  input.width = static_cast<std::uint32_t>(input.jpeg ? video.width() : first.cols);
  input.height = static_cast<std::uint32_t>(input.jpeg ? video.height() : first.rows);
  input.layout = input.jpeg ? imaging::make_layout(input.width, input.height, PixelFormat::mjpeg)
                            : imaging::make_layout(input.width, input.height, PixelFormat::bgr8,
                                                   static_cast<std::uint32_t>(first.step[0]));
  return input;
}

// --fps, else the file's own rate, else 30 (folders and files without a usable rate).
double replay_fps(double asked, const replay::VideoSource& video) {
  const double fps = asked > 0 ? asked : video.fps();
  return fps > 0 && fps <= 10000 ? fps : 30;
}

// The stream of the decoder's frames. A calibration of another size would mislead every
// consumer: it is refused before the stream exists.
Expected<Writer> create_stream(const Options& o, const SensorInfo& described,
                               const ImageLayout& published) {
  if (auto fits = apps::check_calibration_size(described, published.width, published.height);
      !fits) {
    return fits.error();
  }
  StreamSpec spec;
  spec.name = o.stream;
  spec.layout = Layout::of(published);
  spec.checksum = o.checksum;
  spec.sensor = described;
  return Writer::create(spec);
}

// The line said when the replay starts: source, size, rate and stream.
std::string started_line(const Options& o, const replay::VideoSource& video, const Input& input,
                         double fps, const ImageLayout& published) {
  char started[512];
  std::snprintf(started, sizeof started, "%s, %ux%u%s at %.4g fps x %.3g -> %s (%s)%s",
                video.describe().c_str(), input.width, input.height, input.jpeg ? " MJPEG" : "",
                fps, o.rate, o.stream.c_str(), Layout::of(published).describe().c_str(),
                o.loop ? ", looping" : "");
  return started;
}

// One replay's moving parts, for the loop below.
struct Replay {
  const Options& options;
  replay::VideoSource& video;
  const Input& input;
  std::int64_t period_ns;
  imaging::FrameDecoder& decoder;
  Writer& writer;
  apps::StatusLine& status;
  const apps::StopSignal& stop;
};

// Decodes `frame` into the slot before its release time and publishes it at that time, so decode
// time does not delay the frame. Whether it was published (false: a corrupt frame, or one of
// another size); nothing when a stop came while waiting.
std::optional<bool> publish_frame(Replay& r, apps::Pacer& pacer, std::int64_t release_ns,
                                  const cv::Mat& frame, std::int64_t receive_ns) {
  sim::Loan loan = r.writer.loan();
  // Pixel frames must keep the first frame's size; JPEG frames are checked by the decoder.
  const bool fits = frame.isContinuous() &&
                    (r.input.jpeg || (frame.cols == static_cast<int>(r.input.width) &&
                                      frame.rows == static_cast<int>(r.input.height) &&
                                      frame.type() == CV_8UC3));
  imaging::DecodeResult decoded;
  if (fits) {
    decoded = r.decoder.decode(
        std::span<const std::byte>(reinterpret_cast<const std::byte*>(frame.data),
                                   frame.total() * frame.elemSize()),
        loan.bytes());
  }
  if (!pacer.wait(release_ns, r.stop)) return std::nullopt;
  return fits && decoded.status == imaging::DecodeStatus::ok &&
         std::move(loan).commit(decoded.size, realtime_ns(), receive_ns) == WriteStatus::ok;
}

struct Counts {
  long long published = 0;
  long long skipped = 0;  // corrupt or misfit frames, never published
  bool rewind_failed = false;
};

// Publishes `frame` and the frames after it until the end (every pass with --loop) or a stop.
// The schedule runs on across loops: frame i of the whole replay is due at i periods.
Counts publish_all(Replay& r, cv::Mat& frame, std::int64_t receive_ns) {
  Counts counts;
  const long long total = r.video.frame_count();
  long long in_pass = 0;
  int pass = 1;
  apps::Pacer pacer(r.options.rate);
  std::int64_t index = 0;
  bool have_frame = true;
  while (have_frame && !r.stop.requested()) {
    const auto published = publish_frame(r, pacer, index * r.period_ns, frame, receive_ns);
    if (!published) break;
    ++(*published ? counts.published : counts.skipped);
    ++index;
    ++in_pass;
    // append(), not "/" + std::to_string(…): GCC 12 -O3 -Wrestrict false positive (GCC bug 105651).
    r.status.update(apps::fields(
        {{"frame", std::to_string(in_pass) + (total > 0 ? std::string("/").append(std::to_string(total)) : "")},
         {"pass", std::to_string(pass)},
         {"published", std::to_string(counts.published)}}));

    have_frame = r.video.next(frame);
    if (!have_frame && r.options.loop && !r.stop.requested()) {
      if (!r.video.rewind()) {
        counts.rewind_failed = true;
        return counts;
      }
      ++pass;
      in_pass = 0;
      have_frame = r.video.next(frame);
    }
    receive_ns = realtime_ns();  // when the frame's bytes came off the file
  }
  return counts;
}

}  // namespace

int main(int argc, char** argv) {
  apps::CommandLine cli("sim_replay_video",
                        "Replays a video file (anything FFmpeg decodes) or a folder of images "
                        "into a SIM image stream at the recorded rate.");
  Options options;
  add_options(cli, options);
  if (auto code = cli.parse(argc, argv)) return *code;
  auto described = replayed_sensor(options);
  if (!described) return cli.fail(described.error());
  const auto output = *imaging::parse_output_format(options.output_text);
  // Before the stream exists: a reader may see it and stop us at once.
  const auto& stop = apps::StopSignal::install();
  if (auto code = cli.apply_placement(options.placement)) return *code;

  auto source = replay::VideoSource::open(options.path);
  if (!source) return cli.fail(std::string_view(source.error().message));
  auto& video = *source.value();
  cv::Mat frame;
  if (!video.next(frame)) return cli.fail(options.path + " has no frame that can be decoded");
  const std::int64_t receive_ns = realtime_ns();  // when the frame's bytes came off the file
  const Input input = input_of(video, frame);
  if (!input.jpeg && frame.type() != CV_8UC3) {
    return cli.fail(options.path + " does not decode to 8-bit colour frames");
  }
  const double fps = replay_fps(options.fps, video);

  // The decoder the live cameras use: JPEG bytes like a UVC camera's, or BGR pixels.
  auto decoder = imaging::FrameDecoder::create(input.layout, output);
  if (!decoder) return cli.fail(decoder.error());
  const ImageLayout published = decoder->output_layout();
  auto writer = create_stream(options, *described, published);
  if (!writer) return cli.fail(writer.error());

  auto status = apps::StatusLine::for_stderr("sim_replay_video", options.quiet);
  if (!options.quiet) status.note(started_line(options, video, input, fps, published));
  Replay run{options, video, input, static_cast<std::int64_t>(std::llround(1e9 / fps)),
             *decoder, *writer, status, stop};
  const Counts counts = publish_all(run, frame, receive_ns);
  if (counts.rewind_failed) return cli.fail("cannot reopen " + options.path + " to loop it");
  status.finish("published " + std::to_string(counts.published) + " frames" +
                (counts.skipped > 0
                     ? ", skipped " + std::to_string(counts.skipped) + " corrupt or misfit"
                     : ""));
  return apps::kExitOk;
}
