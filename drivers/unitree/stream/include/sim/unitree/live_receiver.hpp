// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: a Unitree L1's or L2's bytes into a LidarStream, the live end of the driver.
// The bytes come from UDP (the L2's default, or an L1 behind its serial-to-UDP board) or a
// serial port (the L1 always, the L2 in serial work mode); each chunk that arrives is pushed
// with its arrival time, whatever it holds (see LidarStream::push).
//
//   auto receiver = sim::unitree::LiveReceiver::open(source, model);  // nothing else is created
//   if (!receiver) -> receiver.error().message (one sentence; invalid_argument: a bad address
//                     or baud rate)
//   receiver->publish_to(stream, record);    // after the stream exists
//   receiver->run(stop_fd, print_status);    // until stop_fd is readable or the port fails
//
// The source is opened before the stream is created, so a busy port or a missing device leaves
// no stream behind. UDP is the lidar::UdpReceiver every family receives with (recvmmsg batches,
// the kernel's arrival stamp of each datagram, a large receive buffer, the sender filter and its
// messages); its handler is not a lidar::LiveReceiver<Route>, because a Unitree datagram is any
// cut of the sensor's byte stream, not one packet to route: every payload goes to the one push.
// The serial port is a plain POSIX terminal (raw 8N1, no flow control) read in a poll() loop.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>

#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"
#include "sim/unitree/decoder.hpp"
#include "sim/unitree/lidar_stream.hpp"

namespace sim::unitree {

struct NetworkConfig {
  std::string bind = "0.0.0.0";  // local address to listen on
  std::uint16_t data_port = 6201;  // 0: a free port, read back with LiveReceiver::port()
  std::string source;            // the lidar's address: datagrams from others are dropped; empty: anyone
};

struct LiveSource {
  std::string serial_device;  // given: read this serial port instead of UDP
  unsigned baud = 0;          // 0: 2,000,000 for the L1, 4,000,000 for the L2
  NetworkConfig network;
};

// What is wrong with a serial baud rate ("--baud 12345 is not a rate a serial port can be set
// to; …"), or "" when termios has a speed for it (0: the model's default).
std::string baud_problem(unsigned baud);

class LiveReceiver {
 public:
  // Opens the serial port (or binds the UDP socket). Errors: invalid_argument for an address
  // that is not one or a baud rate the port cannot take, system_error for a port in use or a
  // device that cannot be opened.
  static Expected<LiveReceiver> open(const LiveSource& source, Model model);

  LiveReceiver(LiveReceiver&&) noexcept;
  LiveReceiver& operator=(LiveReceiver&&) noexcept;
  LiveReceiver(const LiveReceiver&) = delete;
  LiveReceiver& operator=(const LiveReceiver&) = delete;
  ~LiveReceiver();

  // Where the bytes go: the stream, and every byte as received to `record` when given (both
  // must outlive run()). Bytes flow only from run() on.
  void publish_to(LidarStream& stream, std::ostream* record = nullptr) noexcept;

  // Receives until `stop_fd` becomes readable (an eventfd a signal handler writes), calling
  // `tick` about once a second (a status line); the stream's clock record is written and the
  // recording flushed then too, also when no bytes come. `note`: a sentence for the user (a
  // second sender on the UDP port). An error (one sentence) when the serial port fails
  // (unplugged, closed by the other side).
  Expected<void> run(int stop_fd, const std::function<void()>& tick,
                     const std::function<void(std::string_view)>& note = {});

  // "listening on udp port 6201" or "reading /dev/ttyUSB0 at 2000000 baud": printed on stdout
  // by the program, for scripts and tests that bind port 0.
  std::string where() const;
  std::uint16_t port() const noexcept;  // the bound UDP port; 0 when reading a serial port
  // Datagrams from another sender than the lidar: with NetworkConfig::source, those from any
  // other address (dropped; ReceiveCounters::other_source); without it, those from another
  // address than the first one heard (decoded with it, and said once; other_senders).
  std::uint64_t other_senders() const noexcept;
  // The UDP receiver's counters (all zero when reading a serial port).
  lidar::ReceiveCounters counters() const noexcept;

  struct Impl;

 private:
  explicit LiveReceiver(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::unitree
