// SPDX-License-Identifier: Apache-2.0
// SIM streams inside a Boost.Asio event loop: a StreamNotifier's file descriptor is watched like a
// socket, and each wake-up reads the streams that have new frames.
//
//   sim_example_asio_waitset                 demo: publishes 2 streams itself, exits when done
//   sim_example_asio_waitset /cam /lidar     prints every new frame of existing streams (Ctrl-C)
// Boost 1.74's asio/awaitable.hpp uses std::exchange without including <utility> (C++20).
#include <utility>

#include <boost/asio.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "sim/sim.hpp"

namespace asio = boost::asio;

namespace {

struct Loop {
  asio::io_context io;
  asio::posix::stream_descriptor fd;
  sim::StreamNotifier notifier;
  std::vector<sim::Reader> readers;
  std::vector<std::byte> buffer;
  std::vector<std::uint64_t> received;
  std::vector<std::uint64_t> last_seq;
  std::uint64_t stop_after;  // stop once every stream reached this frame number; 0: never

  Loop(sim::StreamNotifier n, std::vector<sim::Reader> r, std::uint64_t frames)
      : fd(io, ::dup(n.fd())), notifier(std::move(n)), readers(std::move(r)),
        received(readers.size(), 0), last_seq(readers.size(), 0), stop_after(frames) {}

  void arm() {
    fd.async_wait(asio::posix::stream_descriptor::wait_read, [this](const boost::system::error_code& ec) {
      if (ec) return;
      const std::vector<bool> arrived = notifier.drain();
      for (std::size_t i = 0; i < readers.size(); ++i) {
        if (!arrived[i]) continue;
        buffer.resize(readers[i].capacity());
        sim::FrameInfo info;
        while (readers[i].read(buffer, info) == sim::ReadStatus::new_frame) {
          ++received[i];
          last_seq[i] = info.seq;
          if (stop_after == 0) {
            std::printf("%s seq=%llu size=%llu\n", readers[i].name().c_str(),
                        static_cast<unsigned long long>(info.seq),
                        static_cast<unsigned long long>(info.size));
          }
        }
      }
      if (stop_after != 0 && done()) {
        io.stop();
        return;
      }
      arm();
    });
  }

  bool done() const {
    for (std::size_t i = 0; i < readers.size(); ++i) {
      if (last_seq[i] < stop_after) return false;
    }
    return true;
  }
};

int run(const std::vector<std::string>& names, std::uint64_t frames) {
  std::vector<sim::Reader> readers;
  for (const std::string& name : names) {
    auto reader = sim::Reader::open(name);
    if (!reader) {
      std::fprintf(stderr, "%s\n", reader.error().message.c_str());
      return 1;
    }
    readers.push_back(std::move(*reader));
  }
  auto notifier = sim::StreamNotifier::open(names);
  if (!notifier) {
    std::fprintf(stderr, "%s\n", notifier.error().message.c_str());
    return 1;
  }
  Loop loop(std::move(*notifier), std::move(readers), frames);
  asio::signal_set signals(loop.io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) { loop.io.stop(); });
  loop.arm();
  loop.io.run();
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::printf("%s: %llu frames\n", names[i].c_str(), static_cast<unsigned long long>(loop.received[i]));
  }
  return frames == 0 || loop.done() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf("usage: %s [STREAM...]\n  no streams: a demo that publishes two streams itself\n", argv[0]);
    return 0;
  }
  if (argc > 1) return run(std::vector<std::string>(argv + 1, argv + argc), 0);

  // The demo: a camera-like and a LiDAR-like stream at different rates, in this process.
  const std::string pid = std::to_string(getpid());
  const std::vector<std::string> names = {"/asio_demo_camera_" + pid, "/asio_demo_lidar_" + pid};
  constexpr std::uint64_t kFrames = 20;
  std::vector<sim::Writer> writers;
  for (const std::string& name : names) {
    auto writer = sim::Writer::create({.name = name, .capacity = 4096});
    if (!writer) {
      std::fprintf(stderr, "%s\n", writer.error().message.c_str());
      return 1;
    }
    writers.push_back(std::move(*writer));
  }
  std::thread publisher([&] {
    std::vector<std::byte> frame(1024);
    for (std::uint64_t i = 0; i < 3 * kFrames; ++i) {
      (void)writers[0].write(std::span<const std::byte>(frame), sim::realtime_ns());
      if (i % 3 == 0) (void)writers[1].write(std::span<const std::byte>(frame), sim::realtime_ns());
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  const int rc = run(names, kFrames);
  publisher.join();
  for (const std::string& name : names) (void)sim::destroy(name, /*force=*/true);
  return rc;
}
