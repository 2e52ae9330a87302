// SPDX-License-Identifier: Apache-2.0
// A camera for the record/play tests and the keep-up measurement: writes --frames BGR images of
// --width x --height at --fps into a SIM stream on an absolute schedule, each frame's bytes and
// stamp given by its index (test_frames.hpp). With --wait-for-reader it creates the stream, says
// "ready" and writes only once a reader waits on it (sim_record has opened it). --noise writes
// random pixels instead, the worst case for compression (tests/mcap/keep_up.sh).
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>

#include "sim/apps/command_line.hpp"
#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "sim/writer.hpp"
#include "test_frames.hpp"

int main(int argc, char** argv) {
  sim::apps::CommandLine cli("mcap_test_camera", "Test camera: deterministic BGR frames into a SIM stream.");
  std::string stream;
  std::uint32_t width = 64, height = 48;
  std::uint64_t frames = 10;
  double fps = 30;
  bool wait_for_reader = false;
  bool noise = false;
  cli.add_option("--stream", stream, "SIM stream to write").required();
  cli.add_option("--width", width, "frame width");
  cli.add_option("--height", height, "frame height");
  cli.add_option("--frames", frames, "0: until killed");
  cli.add_option("--fps", fps, "frames per second").positive();
  cli.add_flag("--wait-for-reader", wait_for_reader, "write only once a reader waits");
  cli.add_flag("--noise", noise, "random pixels (incompressible) instead of the test pattern");
  bool calibrated = false;
  cli.add_flag("--calibrated", calibrated,
               "describe the sensor: frame test_camera_optical on base_link, the calibration of "
               "test_frames.hpp (test_calibration)");
  bool clock = false;
  cli.add_flag("--clock", clock,
               "report a clock: test_camera_clock(false) from the start, test_camera_clock(true) "
               "from the middle frame on (test_frames.hpp)");
  if (auto code = cli.parse(argc, argv)) return *code;

  const auto layout = sim::ImageLayout::packed(width, height, sim::PixelFormat::bgr8);
  std::optional<sim::SensorInfo> sensor;
  if (calibrated) sensor = sim::testing::test_camera_sensor(width, height);
  auto writer = sim::Writer::create({.name = stream, .layout = sim::Layout::of(layout), .sensor = sensor});
  if (!writer) {
    std::fprintf(stderr, "mcap_test_camera: %s\n", writer.error().message.c_str());
    return 1;
  }
  if (clock && !writer->set_clock(sim::testing::test_camera_clock(false))) return 1;
  std::printf("ready\n");
  std::fflush(stdout);
  while (wait_for_reader) {
    auto status = sim::inspect(stream);
    if (status && status->sleeping_readers > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const std::int64_t start = sim::monotonic_ns();
  const auto period = static_cast<std::int64_t>(1e9 / fps);
  std::uint64_t i = 0;
  for (; frames == 0 || i < frames; ++i) {
    const std::int64_t due = start + static_cast<std::int64_t>(i) * period;
    const timespec ts{static_cast<time_t>(due / 1'000'000'000), static_cast<long>(due % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    if (clock && frames > 0 && i == frames / 2 && !writer->set_clock(sim::testing::test_camera_clock(true))) {
      return 1;
    }
    sim::Loan loan = writer->loan();
    if (noise) {
      sim::testing::fill_noise(loan.bytes().first(layout.frame_bytes()), i);
    } else {
      sim::testing::fill_test_image(loan.bytes(), layout.stride, height, i);
    }
    (void)std::move(loan).commit(layout.frame_bytes(), sim::testing::test_image_stamp(i));
  }
  std::printf("done frames=%llu\n", static_cast<unsigned long long>(i));
  // Stay a moment so the last frame is not taken for a dead writer's while it is recorded.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  return 0;
}
