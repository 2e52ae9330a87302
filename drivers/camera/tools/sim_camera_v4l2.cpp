// SPDX-License-Identifier: Apache-2.0
// sim_camera_v4l2: a USB (UVC) or other V4L2 camera into a SIM image stream.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "camera_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/timing/host_clock.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/camera/v4l2_capture.hpp"
#include "sim/camera/v4l2_device.hpp"
#include "sim/camera/v4l2_io.hpp"

namespace {

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
  sim::apps::CommandLine cli(
      "sim_camera_v4l2",
      "Captures a V4L2 camera (USB/UVC) into a SIM image stream, decoding YUYV, UYVY, MJPEG or "
      "grey frames straight into shared memory. The stream stays while the camera is "
      "unplugged; capture resumes when it returns.");
  V4l2Options o;
  add_v4l2_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (auto problem = finish_v4l2_options(o)) return cli.usage_error(*problem);
  V4l2CaptureConfig& config = o.config;

  const auto io = make_libv4l2_io();
  if (o.list_formats || o.list_controls) {
    auto opened = V4l2Device::open(*io, config.device);
    if (!opened) return cli.fail(std::string_view(opened.error().message));
    if (o.list_formats) list_formats(*opened);
    if (o.list_controls) list_controls(*opened);
    return sim::apps::kExitOk;
  }
  // Before the stream exists: a reader may see it and stop us while we are still starting.
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(o.placement)) return *code;

  auto status = sim::apps::StatusLine::for_stderr("sim_camera_v4l2", o.quiet);
  config.log = [&status](std::string_view message) { status.note(message); };
  // The host's clock for the stream's clock check, read once a second on its own thread; started
  // once the camera is, so a failing start says one sentence only. The check asks it from the
  // capture's thread: through an atomic pointer.
  std::unique_ptr<const sim::timing::HostClockWatch> host_watch;
  std::atomic<const sim::timing::HostClockWatch*> host_clock{nullptr};
  config.host_clock = [&host_clock] {
    const auto* watch = host_clock.load();
    return watch != nullptr ? watch->latest() : sim::ClockStatus{};
  };
  auto capture = V4l2Capture::start(*io, config);
  if (!capture) return cli.fail(capture.error());
  sim::timing::HostClockWatchOptions host_options;
  host_options.clock = o.clock.host;
  if (o.quiet) host_options.log = [](const std::string&) {};  // else its own lines on stderr
  host_watch = std::make_unique<const sim::timing::HostClockWatch>(host_options);
  host_clock.store(host_watch.get());
  const auto& layout = capture->output_layout();
  char started[512];
  std::snprintf(started, sizeof started, "%s %s %ux%u at %.4g fps -> %s (%s)",
                config.device.c_str(), capture->format().fourcc.str().c_str(),
                capture->format().layout.width, capture->format().layout.height,
                capture->format().fps, config.stream.c_str(),
                sim::Layout::of(layout).describe().c_str());
  if (!o.quiet) status.note(started);

  auto last_tick = std::chrono::steady_clock::now();
  std::uint64_t last_published = 0;
  capture->run(stop.flag(), [&](StepResult, const V4l2Capture& c) {
    if (!status.due()) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - last_tick).count();
    const auto& s = c.stats();
    status.update(sim::apps::fields(
        {{"frames", std::to_string(s.published)},
         {"rate", sim::apps::number(static_cast<double>(s.published - last_published) / elapsed) +
                      " Hz"},
         {"dropped", std::to_string(s.dropped)},
         {"corrupt", std::to_string(s.corrupt)},
         {"bad_size", std::to_string(s.bad_size)},
         {"camera", c.connected() ? "connected" : "waiting"}}));
    last_tick = now;
    last_published = s.published;
  });
  const auto& s = capture->stats();
  status.finish(sim::apps::fields({{"frames", std::to_string(s.published)},
                                   {"dropped", std::to_string(s.dropped)},
                                   {"corrupt", std::to_string(s.corrupt)},
                                   {"reconnects", std::to_string(s.reconnects)}}));
  return sim::apps::kExitOk;
}
