// SPDX-License-Identifier: Apache-2.0
// UdpReceiver: the UDP side every live LiDAR receiver shares (Hesai, Velodyne, Ouster,
// Unitree). The family's receiver keeps what it knows (which packet is which, the model, the
// stream) and hands each datagram's handling to this loop:
//
//   auto udp = sim::lidar::UdpReceiver::open(listen, ports, 9000);  // sockets, nothing else
//   if (!udp) -> udp.error().message (invalid_argument: a bad address; system_error: a port in use)
//   udp->run(stop_fd, handler, callbacks);  // until stop_fd is readable or the handler says stop
//
// Each socket asks for a large receive buffer (a revolution arrives in bursts; Ouster's
// datagrams are 6–33 kB), joins the multicast group when given and stamps each datagram's
// arrival in the kernel (SO_TIMESTAMPNS). Datagrams are taken in recvmmsg batches into buffers
// allocated once: no allocation and no system call per packet beyond the batch's recvmmsg.
#pragma once

#include <sys/socket.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "sim/result.hpp"

namespace sim::lidar {

enum class IpVersions { v4, v4_and_v6 };

// What is wrong with an address ("'x' is not an IPv4 address (e.g. 192.168.1.201)"), or "" when
// it is one: for checking a value before anything is opened.
std::string address_problem(const std::string& address, IpVersions versions);
// The same for a multicast group address.
std::string multicast_group_problem(const std::string& group, IpVersions versions);

// Where a receiver listens and whom it hears; the same for each of its sockets.
struct UdpListen {
  // Local address to receive on; with a multicast group, the address of the interface to join
  // the group on (the socket then takes the group's datagrams on any address).
  std::string bind = "0.0.0.0";
  std::string multicast_group{};  // empty: unicast or broadcast; given: only this group's datagrams
  std::string source{};           // empty: datagrams from any sender
  int receive_buffer = 8 << 20;   // SO_RCVBUF asked for per socket (SO_RCVBUFFORCE when root)
  IpVersions versions = IpVersions::v4;
  // A gap this long between the sensor's datagrams means it stopped (see resumed_after_silence).
  std::chrono::nanoseconds silence_timeout = std::chrono::milliseconds(500);
  // How the program names `bind` and `source` in its messages (sim_lidar_unitree: --bind-address,
  // --lidar-ip).
  std::string bind_option = "--bind";
  std::string source_option = "--source";
};

// One socket of a receiver, and how messages name it: "UDP port 2368 on 0.0.0.0 is already in
// use by another process (another driver?); stop it or choose another --port."
struct UdpPort {
  std::uint16_t port = 0;        // 0: a free port, read back with UdpReceiver::port()
  std::string what = "UDP";      // "UDP", "the IMU"
  std::string option = "--port"; // the option that chooses it
};

// What the receiver counts, for the status line and the summary; the family's handler counts
// the last three.
struct ReceiveCounters {
  std::uint64_t datagrams = 0;     // every datagram taken from the sockets
  std::uint64_t other_source = 0;  // from another sender than UdpListen::source (dropped)
  // Without a source: from another sender than the first one heard (a second sensor on the
  // port, decoded with the first's; handled, counted, noted once as a warning).
  std::uint64_t other_senders = 0;
  std::uint64_t unrecognised = 0;  // not a packet of the family, before the model was known
  std::uint64_t oversized = 0;     // larger than any packet of the family (cut by the buffer)
  std::uint64_t resumes = 0;       // datagrams came back after a silence
};

// " other-source 3 unrecognised 1" for a status line: the counters that are not zero and tell
// of a problem (the number of datagrams and resumes are the family's business).
std::string describe_problems(const ReceiveCounters& counters);

// What run() tells the program while it runs; each part is optional.
struct ReceiverCallbacks {
  // One sentence for the user: the model detected, packets resumed after a silence.
  std::function<void(std::string_view)> note;
  // Called every tick_period (0: never), to print a status line.
  std::chrono::nanoseconds tick_period{0};
  std::function<void()> tick;
};

// One datagram as the kernel handed it over; valid during the handler's call only.
struct Datagram {
  std::size_t socket = 0;                 // index of its UdpPort in open()'s ports
  std::span<const std::uint8_t> payload;  // cut to the buffer when truncated
  bool truncated = false;                 // larger than the buffer
  std::int64_t arrival_ns = 0;            // CLOCK_REALTIME of its arrival, the kernel's stamp
  std::int64_t taken_ns = 0;              // CLOCK_MONOTONIC when its batch was taken
  const sockaddr_storage* sender = nullptr;
};

// The family's side of the loop. A handler overrides on_datagrams (one call a batch: the
// family's per-datagram work inline, as LiveReceiver<Route> does) or on_datagram.
class DatagramHandler {
 public:
  // The datagrams of one recvmmsg batch from accepted senders, in arrival order; false ends
  // run() (e.g. the stream for a detected model could not be created).
  virtual bool on_datagrams(std::span<const Datagram> datagrams) {
    for (const Datagram& d : datagrams) {
      if (!on_datagram(d)) return false;
    }
    return true;
  }
  // One datagram from an accepted sender; false ends run().
  virtual bool on_datagram(const Datagram& /*datagram*/) { return true; }
  // How long the loop may nap before it looks at the sockets again (packets wait in the socket
  // buffer meanwhile), in ns; 0: wake for each packet. Asked only after a wake-up that took
  // datagrams: a sensor that stopped is waited for, not polled.
  virtual std::int64_t nap_ns() const { return 0; }

 protected:
  ~DatagramHandler() = default;
};

class UdpReceiver {
 public:
  // Checks the addresses, opens, configures and binds a socket per port (joining the multicast
  // group when given), with recvmmsg batches of `batch_size` buffers of `datagram_size` bytes (a
  // buffer larger than the family's largest packet lets an oversized datagram arrive whole and
  // be refused by its size instead of cut to a plausible one). Creates no stream: a busy port
  // leaves nothing behind. Errors: invalid_argument for an address that is not one,
  // system_error for a port in use or a socket the system refuses.
  static Expected<UdpReceiver> open(const UdpListen& listen, std::span<const UdpPort> ports,
                                    std::size_t datagram_size, std::size_t batch_size = 32);

  UdpReceiver(UdpReceiver&&) noexcept;
  UdpReceiver& operator=(UdpReceiver&&) noexcept;
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;
  ~UdpReceiver();

  // Receives until `stop_fd` becomes readable (an eventfd that a signal handler writes; -1:
  // never) or the handler returns false, calling callbacks.tick every callbacks.tick_period.
  void run(int stop_fd, DatagramHandler& handler, const ReceiverCallbacks& callbacks = {});

  // True when a datagram arriving at `arrival_ns` (its kernel stamp) ends a silence longer than
  // the silence timeout: the sensor stopped and sends again. Counts the resume and notes it
  // ("packets resumed after 2.0 s of silence"); the caller forgets the frame in progress.
  // Measured between arrival stamps, not between takes: a stall of this process (packets
  // waiting in the socket buffer) is no silence of the sensor.
  bool resumed_after_silence(std::int64_t arrival_ns);
  // Passes one sentence to the running callbacks' note (nothing outside run()).
  void note(std::string_view message) const;

  std::uint16_t port(std::size_t socket = 0) const noexcept;  // the bound port; 0: no such socket
  std::string local_address(std::size_t socket = 0) const;    // "127.0.0.1:2368"
  int receive_buffer() const noexcept;  // SO_RCVBUF the kernel granted the first socket, bytes
  const ReceiveCounters& counters() const noexcept;
  ReceiveCounters& counters() noexcept;

  struct Impl;

 private:
  explicit UdpReceiver(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// "192.168.1.201" (an IPv4 sender of a dual-stack socket without its ::ffff: prefix).
std::string address_text(const sockaddr_storage& address);

}  // namespace sim::lidar
