// SPDX-License-Identifier: Apache-2.0
// sim_replay_video: replays a video file or a folder of images into a SIM image stream at the
// recorded rate, through the decoder the live camera drivers use.
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
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

int main(int argc, char** argv) {
  using namespace sim;
  apps::CommandLine cli("sim_replay_video",
                        "Replays a video file (anything FFmpeg decodes) or a folder of images "
                        "into a SIM image stream at the recorded rate.");
  auto& app = cli.app();
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
  app.add_option("source", path, "video file, or folder of images played in name order")
      ->required();
  cli.add_stream("--stream", stream, "SIM stream name");
  app.add_option("--fps", fps, "frame rate (0: the file's own, 30 for a folder)")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--rate", rate, "speed factor: 2 plays twice as fast")
      ->check(CLI::Range(0.001, 1000.0));
  app.add_flag("--loop", loop, "start again at the end, until stopped");
  app.add_option("--output", output_text, "published format: bgr8, rgb8 or mono8")
      ->check(CLI::IsMember({"bgr8", "rgb8", "mono8"}));
  app.add_flag("--checksum", checksum, "publish an XXH3 checksum with every frame");
  apps::add_sensor_options(cli, sensor, apps::SensorKind::camera);
  cli.add_placement(placement);
  app.add_flag("-q,--quiet", quiet, "no progress line and no summary");
  if (auto code = cli.parse(argc, argv)) return *code;
  auto described = apps::sensor_info_from(sensor, stream);
  if (!described) return cli.fail(described.error());
  described->time_base = TimeBase::host;
  described->time_sync = "replayed, stamped with this host's clock when published";
  const auto output = *imaging::parse_output_format(output_text);
  // Before the stream exists: a reader may see it and stop us at once.
  const auto& stop = apps::StopSignal::install();
  if (auto code = cli.apply_placement(placement)) return *code;

  auto source = replay::VideoSource::open(path);
  if (!source) return cli.fail(std::string_view(source.error().message));
  auto& video = *source.value();

  cv::Mat frame;
  if (!video.next(frame)) return cli.fail(path + " has no frame that can be decoded");
  std::int64_t receive_ns = realtime_ns();  // when the frame's bytes came off the file
  const bool jpeg = video.jpeg_frames();
  const auto width = static_cast<std::uint32_t>(jpeg ? video.width() : frame.cols);
  const auto height = static_cast<std::uint32_t>(jpeg ? video.height() : frame.rows);
  if (!jpeg && frame.type() != CV_8UC3) {
    return cli.fail(path + " does not decode to 8-bit colour frames");
  }

  if (fps <= 0) fps = video.fps();
  if (!(fps > 0 && fps <= 10000)) fps = 30;  // folders and files without a usable rate
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / fps));

  // The decoder the live cameras use: JPEG bytes like a UVC camera's, or BGR pixels.
  const ImageLayout input =
      jpeg ? imaging::make_layout(width, height, PixelFormat::mjpeg)
           : imaging::make_layout(width, height, PixelFormat::bgr8,
                                  static_cast<std::uint32_t>(frame.step[0]));
  auto decoder = imaging::FrameDecoder::create(input, output);
  if (!decoder) return cli.fail(decoder.error());
  // A calibration of another size would mislead every consumer: refused before the stream exists.
  if (auto fits = apps::check_calibration_size(*described, decoder->output_layout().width,
                                               decoder->output_layout().height);
      !fits) {
    return cli.fail(fits.error());
  }
  StreamSpec spec;
  spec.name = stream;
  spec.layout = Layout::of(decoder->output_layout());
  spec.checksum = checksum;
  spec.sensor = *described;
  auto writer = Writer::create(spec);
  if (!writer) return cli.fail(writer.error());

  auto status = apps::StatusLine::for_stderr("sim_replay_video", quiet);
  char started[512];
  std::snprintf(started, sizeof started, "%s, %ux%u%s at %.4g fps x %.3g -> %s (%s)%s",
                video.describe().c_str(), width, height, jpeg ? " MJPEG" : "", fps, rate,
                stream.c_str(), Layout::of(decoder->output_layout()).describe().c_str(),
                loop ? ", looping" : "");
  if (!quiet) status.note(started);

  const long long total = video.frame_count();
  long long published = 0;
  long long skipped = 0;
  long long in_pass = 0;
  int pass = 1;
  // The schedule runs on across loops: frame i of the whole replay is due at i periods.
  apps::Pacer pacer(rate);
  std::int64_t index = 0;
  bool have_frame = true;
  while (have_frame && !stop.requested()) {
    // Decode into the slot before the deadline, publish at the deadline: decode time does not
    // delay the frame.
    sim::Loan loan = writer->loan();
    // Pixel frames must keep the first frame's size; JPEG frames are checked by the decoder.
    const bool fits = frame.isContinuous() &&
                      (jpeg || (frame.cols == static_cast<int>(width) &&
                                frame.rows == static_cast<int>(height) && frame.type() == CV_8UC3));
    imaging::DecodeResult decoded;
    if (fits) {
      decoded = decoder->decode(
          std::span<const std::byte>(reinterpret_cast<const std::byte*>(frame.data),
                                     frame.total() * frame.elemSize()),
          loan.bytes());
    }
    if (!pacer.wait(index * period_ns, stop)) break;
    if (fits && decoded.status == imaging::DecodeStatus::ok &&
        std::move(loan).commit(decoded.size, realtime_ns(), receive_ns) == WriteStatus::ok) {
      ++published;
    } else {
      ++skipped;  // a corrupt frame, or one of another size: never published
    }
    ++index;
    ++in_pass;
    status.update(apps::fields(
        {{"frame", std::to_string(in_pass) + (total > 0 ? "/" + std::to_string(total) : "")},
         {"pass", std::to_string(pass)},
         {"published", std::to_string(published)}}));

    have_frame = video.next(frame);
    if (!have_frame && loop && !stop.requested()) {
      if (!video.rewind()) return cli.fail("cannot reopen " + path + " to loop it");
      ++pass;
      in_pass = 0;
      have_frame = video.next(frame);
    }
    receive_ns = realtime_ns();
  }
  status.finish("published " + std::to_string(published) + " frames" +
                (skipped > 0 ? ", skipped " + std::to_string(skipped) + " corrupt or misfit" : ""));
  return apps::kExitOk;
}
