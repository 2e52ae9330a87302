// SPDX-License-Identifier: Apache-2.0
#include "sim/velodyne/live_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include "sim/clock.hpp"

namespace sim::velodyne {
namespace {

// Data packets are 1206 bytes, position packets 512 or 554: a larger buffer lets an oversized
// datagram arrive whole and be refused by its size instead of cut to a plausible one.
constexpr std::size_t receive_buffer_size = 2048;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }
Error failed(std::string message) { return Error{ErrorCode::system_error, std::move(message)}; }

std::optional<in_addr> ipv4(const std::string& text) {
  in_addr a{};
  if (inet_pton(AF_INET, text.c_str(), &a) != 1) return std::nullopt;
  return a;
}

// Room for one recvmmsg: payloads, senders and the kernel's receive stamps.
struct ReceiveBatch {
  static constexpr std::size_t size = 32;
  std::vector<std::array<std::uint8_t, receive_buffer_size>> payloads =
      std::vector<std::array<std::uint8_t, receive_buffer_size>>(size);
  std::array<sockaddr_in, size> senders{};
  std::array<iovec, size> vectors{};
  std::array<std::array<char, CMSG_SPACE(sizeof(timespec))>, size> controls{};
  std::array<mmsghdr, size> headers{};

  void prepare() {
    for (std::size_t i = 0; i < size; ++i) {
      vectors[i] = {payloads[i].data(), payloads[i].size()};
      msghdr& h = headers[i].msg_hdr;
      h = {};
      h.msg_name = &senders[i];
      h.msg_namelen = sizeof(sockaddr_in);
      h.msg_iov = &vectors[i];
      h.msg_iovlen = 1;
      h.msg_control = controls[i].data();
      h.msg_controllen = controls[i].size();
      headers[i].msg_len = 0;
    }
  }
  std::span<const std::uint8_t> payload(std::size_t i) const { return {payloads[i].data(), headers[i].msg_len}; }
  std::int64_t arrival_ns(std::size_t i) {
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

class Socket {
 public:
  Socket() = default;
  explicit Socket(int fd) : fd_(fd) {}
  Socket(Socket&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  Socket& operator=(Socket&& o) noexcept {
    if (this != &o) {
      close();
      fd_ = std::exchange(o.fd_, -1);
    }
    return *this;
  }
  ~Socket() { close(); }
  int fd() const noexcept { return fd_; }
  std::uint16_t port() const noexcept {
    sockaddr_in a{};
    socklen_t len = sizeof a;
    if (fd_ < 0 || ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return 0;
    return ntohs(a.sin_port);
  }

 private:
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int fd_ = -1;
};

// A bound UDP socket with arrival stamps and the receive buffer asked for.
Expected<Socket> open_socket(const NetworkConfig& n, std::uint16_t port, int& granted) {
  Socket s(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (s.fd() < 0) return failed(std::string("cannot open a UDP socket: ") + std::strerror(errno) + ".");
  const int on = 1;
  if (!n.multicast_group.empty()) ::setsockopt(s.fd(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  ::setsockopt(s.fd(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  ::setsockopt(s.fd(), SOL_SOCKET, SO_RCVBUF, &n.receive_buffer, sizeof n.receive_buffer);
  socklen_t len = sizeof granted;
  ::getsockopt(s.fd(), SOL_SOCKET, SO_RCVBUF, &granted, &len);
  if (granted < n.receive_buffer) {
    ::setsockopt(s.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &n.receive_buffer, sizeof n.receive_buffer);
    ::getsockopt(s.fd(), SOL_SOCKET, SO_RCVBUF, &granted, &len);
  }
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(port);
  local.sin_addr = *ipv4(n.bind);
  if (::bind(s.fd(), reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    if (errno == EADDRINUSE) {
      return failed("UDP port " + std::to_string(port) + " on " + n.bind +
                    " is already in use by another process (another driver?); stop it or choose another port.");
    }
    return failed("cannot bind to " + n.bind + ":" + std::to_string(port) + ": " + std::strerror(errno) + ".");
  }
  if (!n.multicast_group.empty()) {
    ip_mreq join{};
    join.imr_multiaddr = *ipv4(n.multicast_group);
    join.imr_interface.s_addr = htonl(INADDR_ANY);
    if (::setsockopt(s.fd(), IPPROTO_IP, IP_ADD_MEMBERSHIP, &join, sizeof join) != 0) {
      return failed("cannot join multicast group " + n.multicast_group + ": " + std::strerror(errno) +
                    "; check that an interface with a multicast route exists.");
    }
  }
  return s;
}

timespec as_timespec(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

}  // namespace

std::string address_problem(const std::string& address) {
  if (ipv4(address)) return {};
  return "'" + address + "' is not an IPv4 address (e.g. 192.168.1.201)";
}

std::string multicast_group_problem(const std::string& group) {
  const auto a = ipv4(group);
  if (a && (ntohl(a->s_addr) >> 28) == 0xE) return {};
  return "'" + group + "' is not an IPv4 multicast group address (e.g. 239.255.0.1)";
}

struct LiveReceiver::Impl {
  NetworkConfig network;
  Socket data;
  Socket position;
  std::optional<in_addr> source;
  int granted_buffer = 0;
  ReceiveBatch batch;
  LidarStreamConfig stream_config;
  std::optional<LidarStream> stream;
  std::optional<Error> stream_error;
  const ReceiverCallbacks* callbacks = nullptr;
  ReceiveCounters counters;
  std::int64_t last_packet_ns = 0;
  std::int64_t last_arrival_ns = 0;

  void note(const std::string& message) const {
    if (callbacks != nullptr && callbacks->note) callbacks->note(message);
  }

  bool from_source(std::size_t i) {
    if (!source || batch.senders[i].sin_addr.s_addr == source->s_addr) return true;
    ++counters.other_source;
    return false;
  }

  // Takes every queued datagram of `socket` in batches.
  void take(const Socket& socket, bool is_data) {
    for (;;) {
      batch.prepare();
      const int count = ::recvmmsg(socket.fd(), batch.headers.data(), static_cast<unsigned>(batch.size),
                                   MSG_DONTWAIT, nullptr);
      if (count <= 0) return;  // EAGAIN: all taken; other errors are transient on UDP
      const std::int64_t now = monotonic_ns();
      const auto taken = static_cast<std::size_t>(count);
      for (std::size_t i = 0; i < taken && !stream_error; ++i) {
        ++counters.datagrams;
        if (!from_source(i)) continue;
        if (is_data) {
          on_data(batch.payload(i), batch.arrival_ns(i), now, batch.senders[i]);
        } else if (stream) {
          stream->push_position(batch.payload(i));
        }
      }
      if (taken < batch.size || stream_error) return;
    }
  }

  void on_data(std::span<const std::uint8_t> payload, std::int64_t arrival_ns, std::int64_t now,
               const sockaddr_in& sender) {
    if (!stream) {
      const auto model = detect_model(payload);
      if (!model) {
        ++counters.unrecognised;
        return;
      }
      if (const auto returns = returns_in(payload, *model)) {
        stream_config.returns = std::max(stream_config.returns, *returns);
      }
      char from[INET_ADDRSTRLEN] = "?";
      inet_ntop(AF_INET, &sender.sin_addr, from, sizeof from);
      note("detected a " + std::string(to_string(*model)) + " from " + from);
      if (auto created = create_stream(*model); !created) {
        stream_error = created.error();
        return;
      }
    }
    // Silence between the kernel's arrival stamps, not between takes: a stall of this process
    // (packets waiting in the buffer) is no silence of the sensor.
    if (last_arrival_ns != 0 && arrival_ns - last_arrival_ns > network.silence_timeout.count()) {
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
  if (auto problem = address_problem(network.bind); !problem.empty()) {
    return invalid("the bind address " + problem + "; give the local address to receive on, or 0.0.0.0 for all.");
  }
  auto impl = std::make_unique<Impl>();
  impl->network = network;
  if (!network.source.empty()) {
    if (auto problem = address_problem(network.source); !problem.empty()) {
      return invalid("the source address " + problem + "; give the sensor's address.");
    }
    impl->source = ipv4(network.source);
  }
  if (!network.multicast_group.empty()) {
    if (auto problem = multicast_group_problem(network.multicast_group); !problem.empty()) {
      return invalid("the multicast group " + problem + "; give the group the sensor sends to.");
    }
  }
  auto data = open_socket(network, network.data_port, impl->granted_buffer);
  if (!data) return data.error();
  impl->data = std::move(data.value());
  if (network.position_port) {
    int ignored = 0;
    auto position = open_socket(network, *network.position_port, ignored);
    if (!position) return position.error();
    impl->position = std::move(position.value());
  }
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

Expected<void> LiveReceiver::run(int stop_fd, const ReceiverCallbacks& callbacks) {
  Impl& r = *impl_;
  r.callbacks = &callbacks;
  const std::int64_t tick_ns = callbacks.tick ? callbacks.tick_period.count() : 0;
  std::int64_t next_tick_ns = monotonic_ns() + tick_ns;
  std::array<pollfd, 3> fds{pollfd{stop_fd, POLLIN, 0}, pollfd{r.data.fd(), POLLIN, 0},
                            pollfd{r.position.fd(), POLLIN, 0}};
  const nfds_t count = r.position.fd() >= 0 ? 3 : 2;
  for (;;) {
    for (pollfd& f : fds) f.revents = 0;
    timespec until_tick{};
    const timespec* timeout = nullptr;
    if (tick_ns > 0) {
      until_tick = as_timespec(std::max<std::int64_t>(0, next_tick_ns - monotonic_ns()));
      timeout = &until_tick;
    }
    ::ppoll(fds.data(), count, timeout, nullptr);
    if ((fds[0].revents & POLLIN) != 0) break;
    if ((fds[1].revents & POLLIN) != 0) r.take(r.data, true);
    if (count == 3 && (fds[2].revents & POLLIN) != 0) r.take(r.position, false);
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

std::uint16_t LiveReceiver::data_port() const noexcept { return impl_->data.port(); }
std::uint16_t LiveReceiver::position_port() const noexcept { return impl_->position.port(); }
std::string LiveReceiver::local_address() const { return impl_->network.bind + ":" + std::to_string(data_port()); }
int LiveReceiver::receive_buffer() const noexcept { return impl_->granted_buffer; }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->counters; }
const LidarStream* LiveReceiver::stream() const noexcept { return impl_->stream ? &*impl_->stream : nullptr; }
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::velodyne
