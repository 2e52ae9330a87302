// SPDX-License-Identifier: Apache-2.0
// The C++ side of the Python tests: a writer or reader in another process.
//   sim_python_peer write-image  NAME WIDTH HEIGHT   bgr8 frames until stdin closes
//   sim_python_peer write-points NAME COUNT          LidarPoint frames until stdin closes
//   sim_python_peer read-image   NAME FRAMES         reads FRAMES bgr8 frames, checks every byte
//   sim_python_peer describe     NAME               a camera stream with a full sensor
//                                                   description, one frame, until stdin closes
// Writers print "ready" once the stream exists. Pixel (x, y, c) of frame seq is pixel_value();
// point i of frame seq is expected_point(). The Python tests compute the same values.
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sim/sim.hpp"

namespace {

std::uint8_t pixel_value(std::uint64_t seq, std::uint32_t x, std::uint32_t y, std::uint32_t c) {
  return static_cast<std::uint8_t>((seq * 7 + x * 3 + y * 5 + c) & 0xFF);
}

sim::LidarPoint expected_point(std::uint64_t seq, std::uint32_t i) {
  return {static_cast<float>(i) * 0.5f, -static_cast<float>(i), static_cast<float>(seq),
          static_cast<float>(i % 256), i * 10, static_cast<std::uint16_t>(i % 64),
          static_cast<std::uint8_t>(i % 2), 0};
}

// True once the test closed our stdin (it is done with us).
bool stdin_closed(int wait_ms) {
  pollfd p{STDIN_FILENO, POLLIN, 0};
  if (poll(&p, 1, wait_ms) <= 0) return false;
  char c;
  return read(STDIN_FILENO, &c, 1) <= 0;
}

int fail(const std::string& why) {
  std::fprintf(stderr, "sim_python_peer: %s\n", why.c_str());
  return 1;
}

int write_image(const std::string& name, std::uint32_t width, std::uint32_t height) {
  sim::StreamSpec spec;
  spec.name = name;
  spec.layout = sim::Layout::of(sim::ImageLayout::packed(width, height, sim::PixelFormat::bgr8));
  auto writer = sim::Writer::create(spec);
  if (!writer) return fail(writer.error().message);
  std::vector<std::uint8_t> frame(std::size_t{width} * height * 3);
  std::puts("ready");
  std::fflush(stdout);
  do {
    const std::uint64_t seq = writer->last_seq() + 1;
    for (std::uint32_t y = 0; y < height; ++y)
      for (std::uint32_t x = 0; x < width; ++x)
        for (std::uint32_t c = 0; c < 3; ++c) frame[(std::size_t{y} * width + x) * 3 + c] = pixel_value(seq, x, y, c);
    if (writer->write(std::span<const std::uint8_t>(frame), static_cast<std::int64_t>(seq) * 1000) !=
        sim::WriteStatus::ok) {
      return fail("write refused");
    }
  } while (!stdin_closed(10));
  return 0;
}

int write_points(const std::string& name, std::uint32_t count) {
  sim::StreamSpec spec;
  spec.name = name;
  spec.layout = sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, count * 2));
  auto writer = sim::Writer::create(spec);
  if (!writer) return fail(writer.error().message);
  std::puts("ready");
  std::fflush(stdout);
  do {
    sim::Loan loan = writer->loan();
    const std::uint64_t seq = writer->last_seq() + 1;
    auto points = loan.as<sim::LidarPoint>();
    for (std::uint32_t i = 0; i < count; ++i) points[i] = expected_point(seq, i);
    if (std::move(loan).commit(count * sizeof(sim::LidarPoint), static_cast<std::int64_t>(seq)) !=
        sim::WriteStatus::ok) {
      return fail("commit refused");
    }
  } while (!stdin_closed(10));
  return 0;
}

int read_image(const std::string& name, int frames) {
  auto reader = sim::Reader::open(name);
  if (!reader) return fail(reader.error().message);
  const sim::ImageLayout image = reader->layout().image;
  std::vector<std::byte> buffer(reader->capacity());
  for (int got = 0; got < frames;) {
    sim::FrameInfo info;
    const sim::ReadStatus status = reader->read_next(buffer, info, std::chrono::seconds(10));
    if (status != sim::ReadStatus::new_frame) return fail(std::string("read: ") + sim::to_string(status));
    if (info.size != image.frame_bytes()) return fail("frame of " + std::to_string(info.size) + " bytes");
    for (std::uint32_t y = 0; y < image.height; ++y)
      for (std::uint32_t x = 0; x < image.width; ++x)
        for (std::uint32_t c = 0; c < 3; ++c)
          if (std::to_integer<std::uint8_t>(buffer[std::size_t{y} * image.stride + x * 3 + c]) !=
              pixel_value(info.seq, x, y, c))
            return fail("frame " + std::to_string(info.seq) + " differs at " + std::to_string(x) + "," +
                        std::to_string(y));
    std::printf("frame %llu ok\n", static_cast<unsigned long long>(info.seq));
    std::fflush(stdout);
    ++got;
  }
  return 0;
}

}  // namespace

std::uint32_t number(const std::string& text) { return static_cast<std::uint32_t>(std::stoul(text)); }

// The description test_sensor_info.py expects (camera_from_cpp there).
int describe(const std::string& name) {
  sim::SensorInfo info;
  info.frame_id = "camera_left_optical";
  info.parent_frame = "base_link";
  info.mounting = sim::Mounting::from_xyz_rpy(0.5, 0.25, 1.5, 0.0, 0.0, 0.0);
  sim::CameraCalibration c;
  c.width = 1280;
  c.height = 720;
  c.distortion_model = "rational_polynomial";
  c.d = {0.1, -0.2, 0.001, 0.002, 0.3, 0.01, 0.02, 0.03};
  c.k = {900, 0, 640, 0, 905, 360, 0, 0, 1};
  c.p = {900, 0, 640, 0, 0, 905, 360, 0, 0, 0, 1, 0};
  info.calibration = c;
  info.identity = {"Lucid", "TRI054S", "221000123", "1.64"};
  info.time_base = sim::TimeBase::sensor_synchronized;
  info.time_sync = "PTP slave, locked";
  sim::StreamSpec spec;
  spec.name = name;
  spec.capacity = 64;
  spec.sensor = info;
  auto writer = sim::Writer::create(spec);
  if (!writer) return fail(writer.error().message);
  const std::byte frame[4] = {};
  if (writer->write(frame, sizeof frame, sim::realtime_ns()) != sim::WriteStatus::ok) return fail("write");
  std::printf("ready\n");
  std::fflush(stdout);
  while (!stdin_closed(100)) {
  }
  return 0;
}

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 4 && args[0] == "write-image")
    return write_image(args[1], number(args[2]), number(args[3]));
  if (args.size() == 3 && args[0] == "write-points") return write_points(args[1], number(args[2]));
  if (args.size() == 3 && args[0] == "read-image") return read_image(args[1], std::stoi(args[2]));
  if (args.size() == 2 && args[0] == "describe") return describe(args[1]);
  std::fprintf(stderr, "usage: sim_python_peer write-image NAME W H | write-points NAME N | read-image NAME FRAMES | describe NAME\n");
  return 2;
}
