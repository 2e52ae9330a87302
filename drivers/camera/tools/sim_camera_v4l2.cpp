// SPDX-License-Identifier: Apache-2.0
// sim_camera_v4l2: a USB (UVC) or other V4L2 camera into a SIM image stream.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/camera/config.hpp"
#include "sim/camera/v4l2_capture.hpp"
#include "sim/camera/v4l2_device.hpp"
#include "sim/camera/v4l2_io.hpp"
#include "sim/os.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

using namespace sim::camera;

int list_formats(V4l2Device& device) {
  std::printf("%s (%s)\n", device.path().c_str(), device.card().c_str());
  for (const auto& format : device.formats()) {
    const bool decodable = pixel_format_of(format.fourcc) != sim::PixelFormat::unknown;
    std::printf("  %-4s  %s%s%s\n", format.fourcc.str().c_str(), format.description.c_str(),
                format.compressed ? " (compressed)" : "", decodable ? "" : " (not supported)");
    for (const auto& size : format.sizes) {
      std::printf("        %ux%u", size.width, size.height);
      for (const double fps : size.fps) std::printf(" %.4g", fps);
      std::printf("%s\n", size.fps.empty() ? "" : " fps");
    }
  }
  return 0;
}

int list_controls(V4l2Device& device) {
  std::printf("%s (%s)\n", device.path().c_str(), device.card().c_str());
  for (const auto& control : device.controls()) {
    std::printf("  %-32s %d (min %d, max %d, step %d, default %d)%s\n", control.key.c_str(),
                control.value, control.minimum, control.maximum, control.step,
                control.default_value, control.read_only ? " read-only" : "");
    for (const auto& [index, name] : control.menu) {
      std::printf("  %32s   %d: %s\n", "", index, name.c_str());
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Captures a V4L2 camera (USB/UVC) into a SIM image stream, decoding YUYV, UYVY, "
               "MJPEG or grey frames straight into shared memory.\n"
               "The stream stays while the camera is unplugged; capture resumes when it returns."};
  std::string device;
  std::string config_file;
  std::string stream;
  std::string format_text;
  std::string output_text;
  std::string timestamps_text;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  double fps = 0;
  std::uint32_t buffers = 0;
  std::int64_t time_offset_ns = 0;
  std::vector<std::string> controls;
  int cpu = -1;
  int rt_priority = 0;
  bool list_formats_flag = false;
  bool list_controls_flag = false;
  bool checksum = false;
  bool quiet = false;
  app.add_option("device", device, "Video device node (default /dev/video0 or the config's)");
  app.add_option("--config", config_file, "YAML file with these options (see config/camera/)")
      ->check(CLI::ExistingFile);
  app.add_option("--stream", stream, "SIM stream name (default /camera_front)");
  app.add_option("--format", format_text, "Device format: auto, YUYV, UYVY, MJPG, GREY, Y16, …");
  app.add_option("--width", width, "Frame width (default: the device's current one)");
  app.add_option("--height", height, "Frame height");
  app.add_option("--fps", fps, "Frame rate to request")->check(CLI::Range(0.0, 1000.0));
  app.add_option("--output", output_text, "Published format: bgr8, rgb8, mono8 or raw")
      ->check(CLI::IsMember({"bgr8", "rgb8", "mono8", "raw"}));
  app.add_option("--ctrl", controls, "V4L2 control as name=value (see --list-controls)");
  app.add_option("--buffers", buffers, "Number of mmap buffers (default 4)")
      ->check(CLI::Range(2, 32));
  app.add_option("--timestamps", timestamps_text, "Frame stamps: device (default) or receive")
      ->check(CLI::IsMember({"device", "receive"}));
  app.add_option("--time-offset-ns", time_offset_ns, "Added to every frame stamp");
  app.add_flag("--checksum", checksum, "Publish an XXH3 checksum with every frame");
  app.add_flag("--list-formats", list_formats_flag, "List the device's formats, sizes and rates");
  app.add_flag("--list-controls", list_controls_flag, "List the device's controls");
  app.add_option("--cpu", cpu, "Pin the capture thread to this CPU");
  app.add_option("--rt-priority", rt_priority, "Run under SCHED_FIFO at this priority (1-99)")
      ->check(CLI::Range(1, 99));
  app.add_flag("-q,--quiet", quiet, "No status line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  V4l2CaptureConfig config;
  Placement placement;
  if (!config_file.empty()) {
    if (auto error = load_v4l2_config(config_file, config, placement)) {
      std::fprintf(stderr, "sim_camera_v4l2: %s\n", error->message.c_str());
      return 2;
    }
  }
  if (!device.empty()) config.device = device;
  if (!stream.empty()) config.stream = stream;
  if (!format_text.empty()) {
    if (format_text == "auto") {
      config.format.fourcc.reset();
    } else if (auto fourcc = FourCc::parse(format_text)) {
      config.format.fourcc = fourcc;
    } else {
      std::fprintf(stderr, "sim_camera_v4l2: --format '%s' is not auto or a four-letter code\n",
                   format_text.c_str());
      return 2;
    }
  }
  if (width != 0) config.format.width = width;
  if (height != 0) config.format.height = height;
  if (fps > 0) config.format.fps = fps;
  if (!output_text.empty()) config.format.output = *parse_output_format(output_text);
  if (buffers != 0) config.buffers = buffers;
  if (!timestamps_text.empty()) {
    config.timestamps =
        timestamps_text == "device" ? TimestampSource::device : TimestampSource::receive;
  }
  if (time_offset_ns != 0) config.time_offset_ns = time_offset_ns;
  if (checksum) config.checksum = true;
  for (const auto& control : controls) {
    const auto eq = control.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "sim_camera_v4l2: --ctrl '%s' must be name=value\n", control.c_str());
      return 2;
    }
    config.controls.push_back({control.substr(0, eq), control.substr(eq + 1)});
  }
  if (cpu >= 0) placement.cpu = cpu;
  if (rt_priority > 0) placement.rt_priority = rt_priority;

  const auto io = make_libv4l2_io();
  if (list_formats_flag || list_controls_flag) {
    auto opened = V4l2Device::open(*io, config.device);
    if (!opened) {
      std::fprintf(stderr, "sim_camera_v4l2: %s\n", opened.error().message.c_str());
      return 1;
    }
    if (list_formats_flag) list_formats(*opened);
    if (list_controls_flag) list_controls(*opened);
    return 0;
  }

  if (auto placed = sim::apply_thread_placement(placement); !placed) {
    std::fprintf(stderr, "sim_camera_v4l2: %s\n", placed.error().message.c_str());
    return 1;
  }

  const bool terminal = !quiet && isatty(STDERR_FILENO) != 0;
  config.log = [terminal](std::string_view message) {
    std::fprintf(stderr, "%ssim_camera_v4l2: %.*s\n", terminal ? "\r\033[K" : "",
                 static_cast<int>(message.size()), message.data());
  };
  // Before the stream exists: a reader may see it and stop us while we are still starting.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  auto capture = V4l2Capture::start(*io, config);
  if (!capture) {
    std::fprintf(stderr, "sim_camera_v4l2: %s\n", capture.error().message.c_str());
    return 1;
  }
  const auto& layout = capture->output_layout();
  std::fprintf(stderr, "sim_camera_v4l2: %s %s %ux%u at %.4g fps -> %s (%s)\n",
               config.device.c_str(), capture->format().fourcc.str().c_str(),
               capture->format().layout.width, capture->format().layout.height,
               capture->format().fps, config.stream.c_str(),
               sim::Layout::of(layout).describe().c_str());

  auto last_print = std::chrono::steady_clock::now();
  std::uint64_t last_published = 0;
  capture->run(g_stop, [&](StepResult, const V4l2Capture& c) {
    if (!terminal) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - last_print).count();
    if (elapsed < 1.0) return;
    const auto& s = c.stats();
    std::fprintf(stderr,
                 "\r\033[K%s: %llu frames, %.1f fps, dropped %llu, corrupt %llu, bad size %llu%s",
                 config.stream.c_str(), static_cast<unsigned long long>(s.published),
                 static_cast<double>(s.published - last_published) / elapsed,
                 static_cast<unsigned long long>(s.dropped),
                 static_cast<unsigned long long>(s.corrupt),
                 static_cast<unsigned long long>(s.bad_size),
                 c.connected() ? "" : " (waiting for the camera)");
    last_print = now;
    last_published = s.published;
  });
  if (terminal) std::fprintf(stderr, "\n");
  const auto& s = capture->stats();
  std::fprintf(stderr,
               "sim_camera_v4l2: stopped after %llu frames (dropped %llu, corrupt %llu, "
               "reconnects %llu)\n",
               static_cast<unsigned long long>(s.published),
               static_cast<unsigned long long>(s.dropped),
               static_cast<unsigned long long>(s.corrupt),
               static_cast<unsigned long long>(s.reconnects));
  return 0;
}
