// SPDX-License-Identifier: Apache-2.0
#include "sim/hesai/live_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <span>
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange
#include <vector>

#include <boost/asio.hpp>

#include "sim/clock.hpp"

namespace sim::hesai {
namespace {

namespace asio = boost::asio;
using asio::ip::udp;

// The largest Hesai payload is 1392 bytes; a larger buffer lets an oversized datagram arrive
// whole and be rejected by its size instead of silently cut to a plausible one.
constexpr std::size_t receive_buffer_size = 9000;

// Room for one recvmmsg: payloads, sender addresses and the kernel's receive stamps.
struct ReceiveBatch {
  static constexpr std::size_t size = 32;
  std::vector<std::array<std::uint8_t, receive_buffer_size>> payloads =
      std::vector<std::array<std::uint8_t, receive_buffer_size>>(size);
  std::array<sockaddr_storage, size> senders{};
  std::array<iovec, size> vectors{};
  std::array<std::array<char, CMSG_SPACE(sizeof(timespec))>, size> controls{};
  std::array<mmsghdr, size> headers{};

  // recvmmsg overwrites the lengths; set them again before each call.
  void prepare() {
    for (std::size_t i = 0; i < size; ++i) {
      vectors[i] = {payloads[i].data(), payloads[i].size()};
      msghdr& h = headers[i].msg_hdr;
      h = {};
      h.msg_name = &senders[i];
      h.msg_namelen = sizeof(sockaddr_storage);
      h.msg_iov = &vectors[i];
      h.msg_iovlen = 1;
      h.msg_control = controls[i].data();
      h.msg_controllen = controls[i].size();
      headers[i].msg_len = 0;
    }
  }

  std::span<const std::uint8_t> payload(std::size_t i) const {
    return {payloads[i].data(), headers[i].msg_len};
  }

  asio::ip::address sender(std::size_t i) const {
    const sockaddr_storage& from = senders[i];
    if (from.ss_family == AF_INET6) {
      const auto& v6 = reinterpret_cast<const sockaddr_in6&>(from);
      asio::ip::address_v6::bytes_type bytes;
      std::memcpy(bytes.data(), &v6.sin6_addr, bytes.size());
      const asio::ip::address_v6 address(bytes, v6.sin6_scope_id);
      // A dual-stack socket reports IPv4 senders as ::ffff:a.b.c.d; --source is written as IPv4.
      if (address.is_v4_mapped()) return asio::ip::make_address_v4(asio::ip::v4_mapped, address);
      return address;
    }
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(from);
    return asio::ip::address_v4(ntohl(v4.sin_addr.s_addr));
  }

  // CLOCK_REALTIME of the datagram's arrival, from the kernel; now if it gave none.
  std::int64_t kernel_receive_ns(std::size_t i) {
    msghdr& h = headers[i].msg_hdr;
    for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec t;
        std::memcpy(&t, CMSG_DATA(c), sizeof t);
        return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
      }
    }
    return realtime_ns();
  }
};

timespec as_timespec(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }
Error failed(std::string message) { return Error{ErrorCode::system_error, std::move(message)}; }

}  // namespace

std::string address_problem(const std::string& address) {
  boost::system::error_code ec;
  asio::ip::make_address(address, ec);
  if (!ec) return {};
  return "'" + address + "' is not an IP address (e.g. 192.168.1.201)";
}

std::string multicast_group_problem(const std::string& group) {
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(group, ec);
  if (!ec && address.is_multicast()) return {};
  return "'" + group + "' is not a multicast group address (e.g. 239.255.0.1)";
}

struct LiveReceiver::Impl {
  explicit Impl(NetworkConfig n) : network(std::move(n)), socket(io) {}

  NetworkConfig network;
  asio::io_context io;  // only for the socket's setup; never run (see run())
  udp::socket socket;
  std::optional<asio::ip::address> source;
  int granted_buffer = 0;
  ReceiveBatch batch;

  LidarStreamConfig stream_config;
  std::optional<LidarStream> stream;
  std::optional<Error> stream_error;  // creating the stream for a detected model failed
  const ReceiverCallbacks* callbacks = nullptr;

  ReceiveCounters counters;
  unsigned last_take = 0;             // packets the last take_queued_packets() found
  std::int64_t last_packet_ns = 0;   // monotonic time the last packet was taken
  std::int64_t last_arrival_ns = 0;  // kernel arrival stamp (realtime) of the last packet

  Expected<void> open() {
    if (auto problem = address_problem(network.bind); !problem.empty()) {
      return invalid("the bind address " + problem + "; give the local address to receive on, "
                     "or 0.0.0.0 for all.");
    }
    if (!network.source.empty()) {
      if (auto problem = address_problem(network.source); !problem.empty()) {
        return invalid("the source address " + problem + "; give the sensor's address.");
      }
      source = asio::ip::make_address(network.source);
    }
    std::optional<asio::ip::address> group;
    if (!network.multicast_group.empty()) {
      if (auto problem = multicast_group_problem(network.multicast_group); !problem.empty()) {
        return invalid("the multicast group " + problem + "; give the group the sensor sends to.");
      }
      group = asio::ip::make_address(network.multicast_group);
    }
    boost::system::error_code ec;
    const udp::endpoint local(asio::ip::make_address(network.bind), network.port);
    socket.open(local.protocol(), ec);
    if (ec) return failed("cannot open a UDP socket: " + ec.message() + ".");
    // Several receivers of one multicast group must share the port; a unicast port must not be
    // shared, so two drivers on one port fail loudly instead of splitting the packets.
    if (group) socket.set_option(udp::socket::reuse_address(true), ec);
    set_receive_buffer();
    const int on = 1;
    ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
    socket.bind(local, ec);
    const std::string where = network.bind + ":" + std::to_string(network.port);
    if (ec == asio::error::address_in_use) {
      return failed("UDP port " + std::to_string(network.port) + " on " + network.bind +
                    " is already in use by another process (another driver?); stop it or "
                    "choose another --port.");
    }
    if (ec) return failed("cannot bind to " + where + ": " + ec.message() + "; check --bind and --port.");
    if (group) {
      socket.set_option(asio::ip::multicast::join_group(*group), ec);
      if (ec) {
        return failed("cannot join multicast group " + group->to_string() + ": " + ec.message() +
                      "; check that an interface with a multicast route exists.");
      }
    }
    return {};
  }

  void set_receive_buffer() {
    // A revolution arrives in bursts; at 3600 packets/s a default 200 KiB buffer holds ~50 ms
    // of data, so a short stall of this process would drop packets.
    boost::system::error_code ec;
    socket.set_option(udp::socket::receive_buffer_size(network.receive_buffer), ec);
    udp::socket::receive_buffer_size granted;
    socket.get_option(granted, ec);
    if (granted.value() < network.receive_buffer) {
      // Root may exceed net.core.rmem_max.
      const int wanted = network.receive_buffer;
      ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVBUFFORCE, &wanted, sizeof wanted);
      socket.get_option(granted, ec);
    }
    granted_buffer = granted.value();
  }

  void note(const std::string& message) const {
    if (callbacks != nullptr && callbacks->note) callbacks->note(message);
  }

  // Waking once per packet (6,000 a second for a dual-return Pandar64) costs more CPU than
  // decoding them. Far from the cut no packet can complete a revolution, so the receiver naps
  // and then takes every queued packet in one recvmmsg; near the cut it wakes for each packet.
  // The kernel stamps each datagram's arrival, so batching does not blur receive times.
  //
  // 0: wait for the next packet. A nap ends a margin before the cut can come, and never
  // follows an empty take (the sensor may have stopped: then wait until it sends).
  std::int64_t nap_length_ns() const {
    constexpr std::int64_t longest_nap_ns = 2'000'000;  // ~12 packets; the socket buffer holds seconds
    constexpr std::int64_t wake_margin_ns = 1'000'000;  // timer lateness and motor speed drift
    constexpr std::int64_t shortest_nap_ns = 200'000;   // below this a nap saves nothing
    if (!stream || last_take == 0) return 0;
    const auto to_cut = stream->time_to_cut_ns();
    if (!to_cut) return 0;
    const std::int64_t nap = std::min(longest_nap_ns, *to_cut - wake_margin_ns);
    return nap >= shortest_nap_ns ? nap : 0;
  }

  void take_queued_packets() {
    last_take = 0;
    for (;;) {
      batch.prepare();
      const int count = ::recvmmsg(socket.native_handle(), batch.headers.data(),
                                   static_cast<unsigned>(batch.headers.size()), MSG_DONTWAIT, nullptr);
      // EAGAIN: all taken. Other errors on an unconnected UDP socket are transient (e.g. an
      // ICMP error queued for it); the next wake-up tries again.
      if (count <= 0) return;
      const std::int64_t now = monotonic_ns();
      const auto taken = static_cast<std::size_t>(count);
      for (std::size_t i = 0; i < taken && !stream_error; ++i) {
        on_packet(batch.payload(i), batch.sender(i), batch.kernel_receive_ns(i), now);
      }
      last_take += static_cast<unsigned>(count);
      if (taken < batch.headers.size() || stream_error) return;
    }
  }

  void on_packet(std::span<const std::uint8_t> payload, const asio::ip::address& sender,
                 std::int64_t arrival_ns, std::int64_t now) {
    ++counters.datagrams;
    if (source && sender != *source) {
      ++counters.other_source;
      return;
    }
    if (!stream) {
      // No model given: the first packet that is a Hesai point-cloud packet tells it.
      const auto model = detect_model(payload);
      if (!model) {
        ++counters.unrecognised;
        return;
      }
      if (const auto returns = returns_in(payload, *model)) {
        stream_config.returns = std::max(stream_config.returns, *returns);
      }
      note("detected a " + std::string(to_string(*model)) + " from " + sender.to_string());
      if (auto created = create_stream(*model); !created) {
        stream_error = created.error();
        return;
      }
    }
    // Silence is measured between the kernel's arrival stamps, not between the times this
    // process took the packets: a stall of the receiver (packets waiting in the socket buffer)
    // is no silence of the sensor.
    const std::int64_t silence_ns = network.silence_timeout.count();
    if (last_arrival_ns != 0 && arrival_ns - last_arrival_ns > silence_ns) {
      // The revolution in progress is stale. Readers kept the last frame meanwhile (stale by
      // its publish time); start over with fresh packets.
      stream->reset();
      ++counters.resumes;
      char message[96];
      std::snprintf(message, sizeof message, "packets resumed after %.1f s of silence",
                    static_cast<double>(arrival_ns - last_arrival_ns) / 1e9);
      note(message);
    }
    last_arrival_ns = arrival_ns;
    last_packet_ns = now;
    stream->push(payload, arrival_ns);
  }

  Expected<void> create_stream(Model model) {
    LidarStreamConfig config = stream_config;
    config.assembler.model = model;
    auto created = LidarStream::create(config);
    if (!created) return created.error();
    stream.emplace(std::move(created.value()));
    return {};
  }
};

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  auto impl = std::make_unique<Impl>(network);
  if (auto opened = impl->open(); !opened) return opened.error();
  return LiveReceiver(std::move(impl));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

Expected<void> LiveReceiver::publish_to(LidarStreamConfig config, std::optional<Model> model) {
  impl_->stream.reset();
  impl_->stream_config = std::move(config);
  if (model) return impl_->create_stream(*model);
  return {};
}

// The loop is ppoll rather than io_context::run(): Asio's reactor watches the socket even with
// no read pending, so every datagram would wake a napping receiver.
Expected<void> LiveReceiver::run(int stop_fd, const ReceiverCallbacks& callbacks) {
  Impl& r = *impl_;
  r.callbacks = &callbacks;
  const std::int64_t tick_ns = callbacks.tick ? callbacks.tick_period.count() : 0;
  std::int64_t next_tick_ns = monotonic_ns() + tick_ns;
  std::array<pollfd, 2> fds{pollfd{stop_fd, POLLIN, 0}, pollfd{r.socket.native_handle(), POLLIN, 0}};
  for (;;) {
    fds[0].revents = 0;
    fds[1].revents = 0;
    if (const std::int64_t nap_ns = r.nap_length_ns(); nap_ns > 0) {
      // A nap watches only the stop descriptor: packets wait in the socket buffer.
      const timespec nap = as_timespec(nap_ns);
      ::ppoll(fds.data(), 1, &nap, nullptr);
    } else {
      // Sleep until a datagram arrives, a stop request, or the next tick.
      timespec until_tick{};
      const timespec* timeout = nullptr;
      if (tick_ns > 0) {
        until_tick = as_timespec(std::max<std::int64_t>(0, next_tick_ns - monotonic_ns()));
        timeout = &until_tick;
      }
      ::ppoll(fds.data(), fds.size(), timeout, nullptr);
    }
    if ((fds[0].revents & POLLIN) != 0) break;
    r.take_queued_packets();
    if (r.stream_error) break;
    if (tick_ns > 0 && monotonic_ns() >= next_tick_ns) {
      callbacks.tick();
      next_tick_ns = monotonic_ns() + tick_ns;
    }
  }
  r.callbacks = nullptr;
  if (r.stream_error) return *r.stream_error;
  return {};
}

std::uint16_t LiveReceiver::port() const noexcept {
  boost::system::error_code ec;
  return impl_->socket.local_endpoint(ec).port();
}

std::string LiveReceiver::local_address() const {
  boost::system::error_code ec;
  const udp::endpoint bound = impl_->socket.local_endpoint(ec);
  return bound.address().to_string() + ":" + std::to_string(bound.port());
}

int LiveReceiver::receive_buffer() const noexcept { return impl_->granted_buffer; }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->counters; }
const LidarStream* LiveReceiver::stream() const noexcept {
  return impl_->stream ? &*impl_->stream : nullptr;
}
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::hesai
