// SPDX-License-Identifier: Apache-2.0
// LiveReceiver<Route>: the live end every LiDAR family shares (Hesai, Velodyne, Ouster). The
// family gives its route (a small value type beside its stream: its ports, which datagram goes
// to which push, and how the model is found); the receiver opens the sockets (UdpReceiver) and
// feeds the family's LidarStream:
//
//   auto receiver = lidar::LiveReceiver<velodyne::Route>::open(listen, route);  // sockets only
//   receiver->publish_to(config, model);             // a route that detects the model
//   receiver->run(stop_fd, {.tick = print_status});  // until stop_fd is readable
//   receiver->run(stream, stop_fd, callbacks);       // or into a stream made beforehand (Ouster)
//
// Per data packet: a gap between arrival stamps longer than the silence timeout drops the frame
// in progress (the sensor stopped), then the stream's push, and the packet's sensor time with its
// arrival into the stream's clock check. Far from a revolution's cut (a stream that tells
// time_to_cut_ns) no packet can complete a frame, so the loop naps and takes the queued packets
// at once; near the cut it wakes for each one. All of it inline over the family's types: one
// call from the UDP loop a recvmmsg batch, none a packet.
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "sim/timing/clock_reporter.hpp"
#include "sim/lidar/detected_stream.hpp"
#include "sim/lidar/packet_route.hpp"
#include "sim/lidar/udp_receiver.hpp"
#include "sim/result.hpp"
#include "sim/timing/reported_clock.hpp"

namespace sim::lidar {

// A family's route (hesai::Route, velodyne::Route, ouster::Route), the one routing live and in
// a replay:
//   using Stream                    the family's LidarStream
//   datagram_size, batch_size       the receive buffers (larger than the family's largest packet,
//                                   so an oversized datagram arrives whole and is refused by size)
//   refuse_truncated                a datagram larger than the buffer is counted oversized, not pushed
//   ports()                         the sockets, data first (live: a datagram takes its socket's kind)
//   operator()(port, payload)       which push a datagram to `port` takes (a replay: the
//                                   datagram's destination port)
//   push_other(stream, kind, payload, arrival_ns)   the position and IMU pushes (when it has any)
//   with the model named by the first packet (DetectedStream): using Config, using Model,
//   detect_model(payload), returns_in(payload, model)
//   a stream whose other packets report its clock (Velodyne: stream.reported_clock()):
//   reported_before_stream(), the clock the receiver reports until the stream exists
template <class Route>
concept PacketRoute = requires(const Route& route, std::span<const std::uint8_t> payload) {
  typename Route::Stream;
  { route.ports() } -> std::convertible_to<std::vector<RoutedPort>>;
  { route(std::uint16_t{}, payload) } -> std::same_as<PacketKind>;
  { Route::datagram_size } -> std::convertible_to<std::size_t>;
  { Route::batch_size } -> std::convertible_to<std::size_t>;
  { Route::refuse_truncated } -> std::convertible_to<bool>;
};

template <class Route>
concept DetectsModel = requires(std::span<const std::uint8_t> payload) {
  typename Route::Config;
  typename Route::Model;
  Route::detect_model(payload);
};

namespace detail {
template <class Route>
struct StreamSource {  // a stream given to run()
  typename Route::Stream* get() const noexcept { return nullptr; }
};
template <DetectsModel Route>
struct StreamSource<Route> {
  DetectedStream<typename Route::Stream, typename Route::Config, Route::detect_model, Route::returns_in> detected;
  typename Route::Stream* get() noexcept { return detected.get(); }
  const typename Route::Stream* get() const noexcept { return detected.get(); }
};
}  // namespace detail

template <PacketRoute Route>
class LiveReceiver {
 public:
  using Stream = typename Route::Stream;
  static constexpr bool detects_model = DetectsModel<Route>;
  // The stream's other packets report its clock (Velodyne's position packets).
  static constexpr bool reports_clock = requires(const Stream& s) { s.reported_clock(); };
  // The route has packets besides the data packets (Velodyne's position, Ouster's IMU).
  static constexpr bool has_other_packets =
      requires(Stream& s, std::span<const std::uint8_t> p) { Route::push_other(s, PacketKind::imu, p, std::int64_t{}); };

  // Opens, configures and binds the route's sockets (joining the multicast group when given).
  // Creates no stream: a busy port leaves nothing behind. Errors: invalid_argument for an address
  // that is not one, system_error for a port in use or a socket the system refuses.
  static Expected<LiveReceiver> open(const UdpListen& listen, Route route) {
    const std::vector<RoutedPort> routed = route.ports();
    if (routed.empty() || routed.size() > max_ports) {
      return Error{ErrorCode::invalid_argument, "a route has one to four ports."};
    }
    std::vector<UdpPort> ports;
    std::array<PacketKind, max_ports> kinds{};
    kinds.fill(PacketKind::none);
    for (std::size_t s = 0; s < routed.size(); ++s) {
      ports.push_back(routed[s].udp);
      kinds[s] = routed[s].kind;
    }
    auto udp = UdpReceiver::open(listen, ports, Route::datagram_size, Route::batch_size);
    if (!udp) return udp.error();
    return LiveReceiver(std::move(route), std::move(udp.value()), kinds);
  }

  LiveReceiver(LiveReceiver&&) noexcept = default;
  LiveReceiver& operator=(LiveReceiver&&) noexcept = default;
  LiveReceiver(const LiveReceiver&) = delete;
  LiveReceiver& operator=(const LiveReceiver&) = delete;
  ~LiveReceiver() = default;

  // Where packets go (a route that detects the model). With a model the stream is created now
  // and its error returned (calibration, stream name, a live writer); without one it is created
  // from the first data packet that names the model (its number of returns raises
  // config.returns), and run() returns that error.
  template <class R = Route>
    requires DetectsModel<R>
  Expected<void> publish_to(typename R::Config config, std::optional<typename R::Model> model) {
    clock_sources_given_ = false;
    return source_.detected.publish_to(std::move(config), model);
  }
  // Receives into the stream of publish_to until `stop_fd` becomes readable (an eventfd that a
  // signal handler writes; -1: never). Returns an error only when the stream could not be
  // created for a detected model.
  Expected<void> run(int stop_fd, const ReceiverCallbacks& callbacks = {})
    requires detects_model
  {
    Handler handler{*this};
    udp_.run(stop_fd, handler, callbacks);
    if (const auto& error = source_.detected.error()) return *error;
    return {};
  }
  // Receives into `stream` until `stop_fd` becomes readable (-1: never).
  void run(Stream& stream, int stop_fd, const ReceiverCallbacks& callbacks = {}) {
    given_ = &stream;
    clock_sources_given_ = false;
    Handler handler{*this};
    udp_.run(stop_fd, handler, callbacks);
    given_ = nullptr;
  }

  // What the stream's clock check asks besides its packets: the sensor's own report and the
  // host's clock (ClockSources; each must return its last reading without waiting). Given to
  // the stream at its first data packet; call before run().
  void set_clock_sources(timing::ClockSources sources) {
    clock_sources_ = std::move(sources);
    clock_sources_given_ = false;
  }

  // The bound port of the route's first socket of `kind` (0: none).
  std::uint16_t port(PacketKind kind) const noexcept {
    for (std::size_t s = 0; s < max_ports; ++s) {
      if (kinds_[s] == kind) return udp_.port(s);
    }
    return 0;
  }
  std::uint16_t data_port() const noexcept { return port(PacketKind::data); }
  std::uint16_t position_port() const noexcept { return port(PacketKind::position); }  // 0: none
  std::uint16_t imu_port() const noexcept { return port(PacketKind::imu); }            // 0: none
  std::string local_address() const { return udp_.local_address(0); }  // "127.0.0.1:2368"
  int receive_buffer() const noexcept { return udp_.receive_buffer(); }  // SO_RCVBUF granted, bytes
  const ReceiveCounters& counters() const noexcept { return udp_.counters(); }
  // The stream, once created (nullptr while the model is not known yet, or outside run(stream)).
  const Stream* stream() const noexcept { return current(); }
  std::int64_t last_packet_ns() const noexcept { return last_packet_ns_; }  // CLOCK_MONOTONIC of the last data packet
  const Route& route() const noexcept { return route_; }
  // What the stream's other packets last said of its clock (Stream::reported_clock), valid
  // before the stream exists and from any thread: hand it to the clock reporter.
  timing::ReportedClock reported_clock() const
    requires reports_clock
  {
    return reported_;
  }

 private:
  static constexpr std::size_t max_ports = 4;

  LiveReceiver(Route route, UdpReceiver udp, std::array<PacketKind, max_ports> kinds)
      : route_(std::move(route)), udp_(std::move(udp)), kinds_(kinds) {
    if constexpr (reports_clock) reported_.set(Route::reported_before_stream());
  }

  // Given once, before the stream's first data packet; a stream whose other packets report its
  // clock reports that unless the caller gave another report.
  void give_clock_sources(Stream& stream) {
    if constexpr (reports_clock) {
      timing::ClockSources sources = clock_sources_.value_or(timing::ClockSources{});
      if (!sources.reported) sources.reported = reported_;
      stream.clock().set_sources(std::move(sources));
    } else {
      if (clock_sources_) stream.clock().set_sources(*clock_sources_);
    }
  }

  Stream* current() noexcept {
    if (given_ != nullptr) return given_;
    return source_.get();
  }
  const Stream* current() const noexcept {
    if (given_ != nullptr) return given_;
    return source_.get();
  }

  // The UDP loop's side: one call a batch; each datagram is routed inline. Apart from the
  // receiver, which then has no virtual function (it is moved and destroyed as a value).
  struct Handler final : DatagramHandler {
    explicit Handler(LiveReceiver& r) noexcept : receiver(r) {}
    bool on_datagrams(std::span<const Datagram> datagrams) override {
      for (const Datagram& d : datagrams) {
        if (!receiver.route_datagram(d)) return false;
      }
      return true;
    }
    std::int64_t nap_ns() const override { return receiver.nap_ns(); }
    LiveReceiver& receiver;
  };

  bool route_datagram(const Datagram& d) {
    if constexpr (Route::refuse_truncated) {
      if (d.truncated) {
        ++udp_.counters().oversized;
        return true;
      }
    }
    const PacketKind kind = kinds_[d.socket];
    if (kind != PacketKind::data) {
      if constexpr (has_other_packets) {
        Stream* stream = current();
        if (stream != nullptr && Route::push_other(*stream, kind, d.payload, d.arrival_ns)) {
          if constexpr (reports_clock) reported_.set(stream->reported_clock()());
        }
      }
      return true;
    }
    Stream* stream = nullptr;
    if constexpr (detects_model) {
      stream = given_ != nullptr ? given_ : source_.detected.for_packet(d, udp_);
      if (stream == nullptr) return !source_.detected.error();
    } else {
      stream = given_;
      if (stream == nullptr) return true;
    }
    push_data(*stream, d);
    return true;
  }

  void push_data(Stream& stream, const Datagram& d) {
    if (!clock_sources_given_) {
      give_clock_sources(stream);
      clock_sources_given_ = true;
    }
    // The frame in progress is stale after a silence. Readers kept the last frame meanwhile
    // (stale by its publish time); start over with fresh packets.
    if (udp_.resumed_after_silence(d.arrival_ns)) stream.reset();
    last_packet_ns_ = d.taken_ns;
    const auto result = stream.push(d.payload, d.arrival_ns);
    if constexpr (requires(const Stream& s) { s.mismatch_problem(); }) {
      if (result.error != decltype(result.error){} && !mismatch_noted_) note_mismatch(stream);
    }
    // The packet's own time against its arrival on this host; judged about once a second.
    stream.clock().add(result.packet_ns, stream.stamp_offset(), d.arrival_ns);
    stream.tick_clock(d.arrival_ns);
  }

  // Once: the user must learn that the packets do not fit (Ouster's metadata), not read it
  // hundreds of times a second.
  void note_mismatch(const Stream& stream) {
    const std::string problem = stream.mismatch_problem();
    if (problem.empty()) return;
    udp_.note(problem);
    mismatch_noted_ = true;
  }

  // Waking once per packet (6,000 a second for a dual-return Pandar64) costs more CPU than
  // decoding them. Far from the cut no packet can complete a revolution, so the receiver naps
  // and then takes every queued packet in one recvmmsg; near the cut it wakes for each packet.
  // The kernel stamps each datagram's arrival, so batching does not blur receive times. A nap
  // ends a margin before the cut can come; 0: wait for the next packet.
  std::int64_t nap_ns() const {
    if constexpr (requires(const Stream& s) { s.time_to_cut_ns(); }) {
      constexpr std::int64_t longest_nap_ns = 2'000'000;  // ~12 packets; the socket buffer holds seconds
      constexpr std::int64_t wake_margin_ns = 1'000'000;  // timer lateness and motor speed drift
      constexpr std::int64_t shortest_nap_ns = 200'000;   // below this a nap saves nothing
      const Stream* stream = current();
      if (stream == nullptr) return 0;
      const auto to_cut = stream->time_to_cut_ns();
      if (!to_cut) return 0;
      const std::int64_t nap = std::min(longest_nap_ns, *to_cut - wake_margin_ns);
      return nap >= shortest_nap_ns ? nap : 0;
    } else {
      return 0;
    }
  }

  Route route_;
  UdpReceiver udp_;
  std::array<PacketKind, max_ports> kinds_{};
  detail::StreamSource<Route> source_;
  Stream* given_ = nullptr;  // during run(stream, …)
  std::int64_t last_packet_ns_ = 0;
  std::optional<timing::ClockSources> clock_sources_;
  bool clock_sources_given_ = false;
  timing::ReportedClock reported_;  // reports_clock: the stream's, copied after each report
  bool mismatch_noted_ = false;
};

}  // namespace sim::lidar
