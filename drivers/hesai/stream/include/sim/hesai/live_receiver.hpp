// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: a Hesai sensor's UDP packets into a LidarStream, the live end of the driver.
//
//   auto receiver = sim::hesai::LiveReceiver::open({.data_port = 2368});   // the socket, nothing else
//   if (!receiver) -> receiver.error().message (one sentence; invalid_argument: a bad address)
//   receiver->publish_to(stream_config, model);       // model nullopt: from the first packet
//   receiver->run(stop_fd, {.tick = print_status});   // until stop_fd is readable
//
// The socket takes datagrams in recvmmsg batches with the kernel's arrival stamps
// (SO_TIMESTAMPNS). Far from a revolution's cut no packet can complete a frame, so the receiver
// naps there and takes the queued packets at once (about 12 per wake-up at 6,000 packets/s);
// near the cut it wakes for each packet, so a finished revolution is published as soon as its
// last packet lands. A gap between arrival stamps longer than the silence timeout means the
// sensor stopped: the revolution in progress is dropped and the next packet starts anew.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "sim/hesai/lidar_stream.hpp"
#include "sim/hesai/model.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"

namespace sim::hesai {

struct NetworkConfig {
  // Where to listen and whom to hear: bind, multicast group, source, receive buffer, silence
  // timeout. IPv4 or IPv6 (lidar::address_problem(…, IpVersions::v4_and_v6) checks an address).
  lidar::UdpListen listen{.receive_buffer = 16 << 20, .versions = lidar::IpVersions::v4_and_v6};
  std::uint16_t data_port = 2368;  // 0: a free port, read back with LiveReceiver::data_port()
};

// datagrams, other_source, unrecognised (not a Hesai point-cloud packet, before the model was
// known) and resumes (packets came back after a silence).
using ReceiveCounters = lidar::ReceiveCounters;
// note: the model detected, packets resumed after a silence; tick: a status line.
using ReceiverCallbacks = lidar::ReceiverCallbacks;

class LiveReceiver {
 public:
  // Opens, configures and binds the UDP socket (joining the multicast group when given). Creates
  // no stream: a busy port leaves nothing behind. Errors: invalid_argument for an address that
  // is not one, system_error for a port in use or a socket the system refuses.
  static Expected<LiveReceiver> open(const NetworkConfig& network);

  LiveReceiver(LiveReceiver&&) noexcept;
  LiveReceiver& operator=(LiveReceiver&&) noexcept;
  LiveReceiver(const LiveReceiver&) = delete;
  LiveReceiver& operator=(const LiveReceiver&) = delete;
  ~LiveReceiver();

  // Where packets go. With a model the stream is created now and its error returned (calibration,
  // stream name, a live writer); without one it is created from the first packet that names the
  // model (its number of returns raises config.returns), and run() returns that error.
  Expected<void> publish_to(LidarStreamConfig config, std::optional<Model> model);

  // Receives until `stop_fd` becomes readable (an eventfd that a signal handler writes; -1:
  // never). Returns an error only when the stream could not be created for a detected model.
  Expected<void> run(int stop_fd, const ReceiverCallbacks& callbacks = {});

  // What the stream's clock check asks besides its packets: the sensor's own report and the
  // host's clock (timing::ClockSources; each must return its last reading without waiting).
  // Given to the stream when it is created; call before run().
  void set_clock_sources(timing::ClockSources sources);

  std::uint16_t data_port() const noexcept;        // the bound port
  std::string local_address() const;              // "127.0.0.1:2368"
  int receive_buffer() const noexcept;             // SO_RCVBUF the kernel granted, bytes
  const ReceiveCounters& counters() const noexcept;
  // The stream, once created (nullptr while the model is not known yet).
  const LidarStream* stream() const noexcept;
  // CLOCK_MONOTONIC when the last packet was taken; 0 before the first.
  std::int64_t last_packet_ns() const noexcept;

  struct Impl;

 private:
  explicit LiveReceiver(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::hesai
