// SPDX-License-Identifier: Apache-2.0
// sim_camera_aravis: a GigE Vision or USB3 Vision camera (through Aravis) into a SIM stream.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "camera_options.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/timing/host_clock.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/camera/aravis_capture.hpp"

int main(int argc, char** argv) {
  using namespace sim::camera;
  sim::apps::CommandLine cli(
      "sim_camera_aravis",
      "Captures a GigE Vision or USB3 Vision camera (Aravis) into a SIM image stream, decoding "
      "Mono8/Mono16/Bayer/RGB/YUV422 straight into shared memory. The stream stays while the "
      "camera is lost; capture resumes when it returns.");
  AravisOptions o;
  add_aravis_options(cli, o);
  if (auto code = cli.parse(argc, argv)) return *code;
  if (auto problem = finish_aravis_options(o)) return cli.usage_error(*problem);
  AravisCaptureConfig& config = o.config;
  if (o.list) {
    const auto cameras = AravisCapture::list_cameras();
    if (cameras.empty()) std::printf("no camera found\n");
    for (const auto& camera : cameras) std::printf("%s\n", camera.c_str());
    return sim::apps::kExitOk;
  }
  // Before the stream exists: a reader may see it and stop us while we are still starting.
  const auto& stop = sim::apps::StopSignal::install();
  if (auto code = cli.apply_placement(o.placement)) return *code;
  auto status = sim::apps::StatusLine::for_stderr("sim_camera_aravis", o.quiet);
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
  auto capture = AravisCapture::start(config);
  if (!capture) return cli.fail(capture.error());
  sim::timing::HostClockWatchOptions host_options;
  host_options.clock = o.clock.host;
  if (o.quiet) host_options.log = [](const std::string&) {};  // else its own lines on stderr
  host_watch = std::make_unique<const sim::timing::HostClockWatch>(host_options);
  host_clock.store(host_watch.get());
  if (!o.quiet) {
    status.note(capture->camera_name() + " -> " + config.stream + " (" +
                sim::Layout::of(capture->output_layout()).describe() + ")");
  }
  auto last_tick = std::chrono::steady_clock::now();
  std::uint64_t last_published = 0;
  capture->run(stop.flag(), [&](const AravisCapture& c) {
    if (!status.due()) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - last_tick).count();
    const auto s = c.stats();
    status.update(sim::apps::fields(
        {{"frames", std::to_string(s.published)},
         {"rate", sim::apps::number(static_cast<double>(s.published - last_published) / elapsed) +
                      " Hz"},
         {"incomplete", std::to_string(s.incomplete)},
         {"dropped", std::to_string(s.dropped)},
         {"camera", c.connected() ? "connected" : "waiting"}}));
    last_tick = now;
    last_published = s.published;
  });
  const auto s = capture->stats();
  status.finish(sim::apps::fields({{"frames", std::to_string(s.published)},
                                   {"incomplete", std::to_string(s.incomplete)},
                                   {"dropped", std::to_string(s.dropped)},
                                   {"missing_packets", std::to_string(s.missing_packets)},
                                   {"reconnects", std::to_string(s.reconnects)}}));
  return sim::apps::kExitOk;
}
