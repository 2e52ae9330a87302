// SPDX-License-Identifier: Apache-2.0
// LiveReceiver: a Velodyne sensor's UDP packets into a LidarStream, the live end of the driver.
//
//   auto receiver = sim::velodyne::LiveReceiver::open({.data_port = 2368});  // sockets only
//   receiver->publish_to(stream_config, model);     // model nullopt: from the first packet
//   receiver->run(stop_fd, {.tick = print_status}); // until stop_fd is readable
//
// Two sockets: data packets (2368) and position packets (8308, the GPRMC/PPS state). Datagrams
// are taken in recvmmsg batches with the kernel's arrival stamps (SO_TIMESTAMPNS). A gap
// between arrival stamps longer than the silence timeout means the sensor stopped: the
// revolution in progress is dropped and the next packet starts anew. IPv4.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"
#include "sim/velodyne/lidar_stream.hpp"

namespace sim::velodyne {

struct NetworkConfig {
  // Where to listen and whom to hear: bind, multicast group, source, receive buffer, silence
  // timeout. IPv4 (lidar::address_problem(…, IpVersions::v4) checks an address).
  lidar::UdpListen listen;
  std::uint16_t data_port = default_data_port;  // 0: a free port, read back with data_port()
  std::optional<std::uint16_t> position_port = default_position_port;  // nullopt: not listened to
};

// datagrams (data and position), other_source, unrecognised (not a Velodyne data packet,
// before the model was known) and resumes (packets came back after a silence).
using ReceiveCounters = lidar::ReceiveCounters;
// note: the model detected, packets resumed…; tick: every tick_period, for a status line.
using ReceiverCallbacks = lidar::ReceiverCallbacks;

class LiveReceiver {
 public:
  // Opens and binds the sockets (joining the multicast group); creates no stream. Errors:
  // invalid_argument for an address that is not one, system_error for a port in use.
  static Expected<LiveReceiver> open(const NetworkConfig& network);

  LiveReceiver(LiveReceiver&&) noexcept;
  LiveReceiver& operator=(LiveReceiver&&) noexcept;
  LiveReceiver(const LiveReceiver&) = delete;
  LiveReceiver& operator=(const LiveReceiver&) = delete;
  ~LiveReceiver();

  // With a model the stream is created now (its error returned); without, from the first data
  // packet that names the model (run() returns the error then).
  Expected<void> publish_to(LidarStreamConfig config, std::optional<Model> model);
  Expected<void> run(int stop_fd, const ReceiverCallbacks& callbacks = {});

  // What the stream's clock check asks besides its packets: the sensor's own report and the
  // host's clock (timing::ClockSources; each must return its last reading without waiting).
  // Given to the stream when it is created; call before run().
  void set_clock_sources(timing::ClockSources sources);

  std::uint16_t data_port() const noexcept;
  std::uint16_t position_port() const noexcept;  // 0 when not listened to
  std::string local_address() const;             // "127.0.0.1:2368"
  int receive_buffer() const noexcept;
  const ReceiveCounters& counters() const noexcept;
  const LidarStream* stream() const noexcept;
  // What the position packets last said of the sensor's clock (LidarStream::reported_clock),
  // valid before the stream exists and from any thread: hand it to the clock reporter.
  ReportedClock reported_clock() const;
  std::int64_t last_packet_ns() const noexcept;  // CLOCK_MONOTONIC of the last data packet

  struct Impl;

 private:
  explicit LiveReceiver(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::velodyne
