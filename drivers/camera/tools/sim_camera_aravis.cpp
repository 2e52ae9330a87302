// SPDX-License-Identifier: Apache-2.0
// sim_camera_aravis: a GigE Vision or USB3 Vision camera (through Aravis) into a SIM stream.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/camera/aravis_capture.hpp"
#include "sim/camera/config.hpp"
#include "sim/os.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  using namespace sim::camera;
  CLI::App app{"Captures a GigE Vision or USB3 Vision camera (Aravis) into a SIM image stream, "
               "decoding Mono8/Mono16/Bayer/RGB/YUV422 straight into shared memory.\n"
               "The stream stays while the camera is lost; capture resumes when it returns."};
  AravisCaptureConfig config;
  std::string config_file;
  std::string output_text;
  std::vector<std::string> features;
  std::vector<int> roi;
  bool list = false;
  bool no_packet_socket = false;
  bool quiet = false;
  int cpu = -1;
  int rt_priority = 0;
  app.add_option("device", config.device_id, "Camera id, serial number or IP (default: the first)");
  app.add_option("--config", config_file, "YAML file with these options and GenICam features")
      ->check(CLI::ExistingFile);
  app.add_option("--stream", config.stream, "SIM stream name");
  app.add_option("--pixel-format", config.pixel_format, "GenICam pixel format (Mono8, BayerRG8, …)");
  app.add_option("--output", output_text, "Published format: bgr8, rgb8, mono8 or raw")
      ->check(CLI::IsMember({"bgr8", "rgb8", "mono8", "raw"}));
  app.add_option("--fps", config.fps, "Acquisition frame rate")->check(CLI::Range(0.0, 10000.0));
  app.add_option("--exposure", config.exposure_us, "Exposure time in microseconds")
      ->check(CLI::PositiveNumber);
  app.add_option("--gain", config.gain, "Gain (camera units)")->check(CLI::NonNegativeNumber);
  app.add_option("--roi", roi, "Region of interest: X Y WIDTH HEIGHT")->expected(4);
  app.add_option("--packet-size", config.packet_size, "GigE packet size in bytes")
      ->check(CLI::Range(576, 16000));
  app.add_flag("--no-packet-socket", no_packet_socket,
               "Receive through a plain UDP socket (no CAP_NET_RAW needed; drops more)");
  app.add_option("--feature", features, "Any GenICam feature as Name=value (repeatable)");
  app.add_option("--buffers", config.buffers, "Buffers in the pool")->check(CLI::Range(2, 64));
  app.add_flag("--device-timestamps", config.device_timestamps,
               "Stamp frames with the camera's clock (enable PTP on the camera)");
  app.add_flag("--checksum", config.checksum, "Publish an XXH3 checksum with every frame");
  app.add_flag("--list", list, "List the cameras Aravis finds and exit");
  app.add_option("--cpu", cpu, "Pin the control thread to this CPU");
  app.add_option("--rt-priority", rt_priority, "Run under SCHED_FIFO at this priority (1-99)")
      ->check(CLI::Range(1, 99));
  app.add_flag("-q,--quiet", quiet, "No status line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // The file gives the base; options given on the command line win.
  sim::ThreadPlacement placement;
  if (!config_file.empty()) {
    AravisCaptureConfig base;
    if (auto error = load_aravis_config(config_file, base, placement)) {
      std::fprintf(stderr, "sim_camera_aravis: %s\n", error->message.c_str());
      return 2;
    }
    for (const auto* option : app.get_options()) {
      if (option->count() > 0) continue;
      const std::string name = option->get_name();
      if (name == "device") config.device_id = base.device_id;
      if (name == "--stream") config.stream = base.stream;
      if (name == "--pixel-format") config.pixel_format = base.pixel_format;
      if (name == "--output") output_text = sim::camera::to_string(base.output);
      if (name == "--fps") config.fps = base.fps;
      if (name == "--exposure") config.exposure_us = base.exposure_us;
      if (name == "--gain") config.gain = base.gain;
      if (name == "--packet-size") config.packet_size = base.packet_size;
      if (name == "--buffers") config.buffers = base.buffers;
      if (name == "--roi") {
        config.offset_x = base.offset_x;
        config.offset_y = base.offset_y;
        config.width = base.width;
        config.height = base.height;
      }
    }
    if (!no_packet_socket) no_packet_socket = !base.packet_socket;
    config.device_timestamps = config.device_timestamps || base.device_timestamps;
    config.checksum = config.checksum || base.checksum;
    config.retry_period = base.retry_period;
    config.features = base.features;  // command-line --feature entries follow and win
  }
  config.output = *parse_output_format(output_text.empty() ? "bgr8" : output_text);
  config.packet_socket = !no_packet_socket;
  if (!roi.empty()) {
    config.offset_x = roi[0];
    config.offset_y = roi[1];
    config.width = roi[2];
    config.height = roi[3];
  }
  for (const auto& feature : features) {
    const auto eq = feature.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "sim_camera_aravis: --feature '%s' must be Name=value\n", feature.c_str());
      return 2;
    }
    config.features.emplace_back(feature.substr(0, eq), feature.substr(eq + 1));
  }
  if (list) {
    const auto cameras = AravisCapture::list_cameras();
    if (cameras.empty()) std::printf("no camera found\n");
    for (const auto& camera : cameras) std::printf("%s\n", camera.c_str());
    return 0;
  }
  if (cpu >= 0) placement.cpu = cpu;
  if (rt_priority > 0) placement.rt_priority = rt_priority;
  if (auto placed = sim::apply_thread_placement(placement); !placed) {
    std::fprintf(stderr, "sim_camera_aravis: %s\n", placed.error().message.c_str());
    return 1;
  }
  const bool terminal = !quiet && isatty(STDERR_FILENO) != 0;
  config.log = [terminal](std::string_view message) {
    std::fprintf(stderr, "%ssim_camera_aravis: %.*s\n", terminal ? "\r\033[K" : "",
                 static_cast<int>(message.size()), message.data());
  };
  // Before the stream exists: a reader may see it and stop us while we are still starting.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  auto capture = AravisCapture::start(config);
  if (!capture) {
    std::fprintf(stderr, "sim_camera_aravis: %s\n", capture.error().message.c_str());
    return 1;
  }
  const auto& layout = capture->output_layout();
  std::fprintf(stderr, "sim_camera_aravis: %s -> %s (%s)\n", capture->camera_name().c_str(),
               config.stream.c_str(), sim::Layout::of(layout).describe().c_str());
  auto last_print = std::chrono::steady_clock::now();
  std::uint64_t last_published = 0;
  capture->run(g_stop, [&](const AravisCapture& c) {
    if (!terminal) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - last_print).count();
    if (elapsed < 1.0) return;
    const auto s = c.stats();
    std::fprintf(stderr, "\r\033[K%s: %llu frames, %.1f fps, incomplete %llu, dropped %llu%s",
                 config.stream.c_str(), static_cast<unsigned long long>(s.published),
                 static_cast<double>(s.published - last_published) / elapsed,
                 static_cast<unsigned long long>(s.incomplete),
                 static_cast<unsigned long long>(s.dropped),
                 c.connected() ? "" : " (waiting for the camera)");
    last_print = now;
    last_published = s.published;
  });
  if (terminal) std::fprintf(stderr, "\n");
  const auto s = capture->stats();
  std::fprintf(stderr,
               "sim_camera_aravis: stopped after %llu frames (incomplete %llu, dropped %llu, "
               "missing packets %llu, reconnects %llu)\n",
               static_cast<unsigned long long>(s.published),
               static_cast<unsigned long long>(s.incomplete),
               static_cast<unsigned long long>(s.dropped),
               static_cast<unsigned long long>(s.missing_packets),
               static_cast<unsigned long long>(s.reconnects));
  return 0;
}
