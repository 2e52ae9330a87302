// SPDX-License-Identifier: Apache-2.0
#include "sim/ouster/live_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <span>
#include <vector>

#include "sim/clock.hpp"

namespace sim::ouster {
namespace {

// Larger than the largest Ouster datagram (128 beams, dual profile: 33 kB).
constexpr std::size_t datagram_buffer = 65536;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }
Error failed(std::string message) { return Error{ErrorCode::system_error, std::move(message)}; }

class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) noexcept : fd_(fd) {}
  Fd(Fd&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  Fd& operator=(Fd&& o) noexcept {
    std::swap(fd_, o.fd_);
    return *this;
  }
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const noexcept { return fd_; }

 private:
  int fd_ = -1;
};

// Room for one recvmmsg: payloads, senders and the kernel's receive stamps.
struct ReceiveBatch {
  static constexpr std::size_t size = 16;
  std::vector<std::uint8_t> payloads = std::vector<std::uint8_t>(size * datagram_buffer);
  std::array<sockaddr_in, size> senders{};
  std::array<iovec, size> vectors{};
  std::array<std::array<char, CMSG_SPACE(sizeof(timespec))>, size> controls{};
  std::array<mmsghdr, size> headers{};

  int receive(int fd) {
    for (std::size_t i = 0; i < size; ++i) {
      vectors[i] = {payloads.data() + i * datagram_buffer, datagram_buffer};
      msghdr& h = headers[i].msg_hdr;
      h = {};
      h.msg_name = &senders[i];
      h.msg_namelen = sizeof(sockaddr_in);
      h.msg_iov = &vectors[i];
      h.msg_iovlen = 1;
      h.msg_control = controls[i].data();
      h.msg_controllen = controls[i].size();
    }
    return ::recvmmsg(fd, headers.data(), size, MSG_DONTWAIT, nullptr);
  }
  std::span<const std::uint8_t> payload(std::size_t i) const {
    return {payloads.data() + i * datagram_buffer, headers[i].msg_len};
  }
  bool truncated(std::size_t i) const { return (headers[i].msg_hdr.msg_flags & MSG_TRUNC) != 0; }
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

}  // namespace

std::string ipv4_problem(const std::string& address) {
  in_addr ignored{};
  if (::inet_pton(AF_INET, address.c_str(), &ignored) == 1) return {};
  return "'" + address + "' is not an IPv4 address (e.g. 192.168.1.201)";
}

std::string multicast_group_problem(const std::string& group) {
  in_addr a{};
  if (::inet_pton(AF_INET, group.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 28) == 0xE) return {};
  return "'" + group + "' is not an IPv4 multicast group address (e.g. 239.201.201.201)";
}

struct LiveReceiver::Impl {
  NetworkConfig network;
  Fd lidar;
  Fd imu;
  in_addr source{};
  bool filter_source = false;
  int granted_buffer = 0;
  ReceiveBatch batch;
  ReceiveCounters counters;
  std::int64_t last_packet_ns = 0;
  std::int64_t last_arrival_ns = 0;
  bool mismatch_noted = false;

  Expected<Fd> open_socket(std::uint16_t port, const char* what) {
    Fd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    if (fd.get() < 0) return failed(std::string("cannot open a UDP socket: ") + std::strerror(errno) + ".");
    const int on = 1;
    if (!network.multicast_group.empty()) ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    ::setsockopt(fd.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
    const int wanted = network.receive_buffer;
    ::setsockopt(fd.get(), SOL_SOCKET, SO_RCVBUF, &wanted, sizeof wanted);
    int granted = 0;
    socklen_t length = sizeof granted;
    ::getsockopt(fd.get(), SOL_SOCKET, SO_RCVBUF, &granted, &length);
    if (granted < wanted) {  // root may exceed net.core.rmem_max
      ::setsockopt(fd.get(), SOL_SOCKET, SO_RCVBUFFORCE, &wanted, sizeof wanted);
      ::getsockopt(fd.get(), SOL_SOCKET, SO_RCVBUF, &granted, &length);
    }
    granted_buffer = granted;
    sockaddr_in local{};
    local.sin_family = AF_INET;
    local.sin_port = htons(port);
    ::inet_pton(AF_INET, network.bind.c_str(), &local.sin_addr);
    if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
      const int error = errno;
      if (error == EADDRINUSE) {
        return failed(std::string(what) + " port " + std::to_string(port) + " on " + network.bind +
                      " is already in use by another process (another driver?); stop it or choose "
                      "another port.");
      }
      return failed("cannot bind to " + network.bind + ":" + std::to_string(port) + ": " +
                    std::strerror(error) + "; check --bind and the ports.");
    }
    if (!network.multicast_group.empty()) {
      ip_mreq membership{};
      ::inet_pton(AF_INET, network.multicast_group.c_str(), &membership.imr_multiaddr);
      membership.imr_interface.s_addr = htonl(INADDR_ANY);
      if (::setsockopt(fd.get(), IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0) {
        return failed("cannot join multicast group " + network.multicast_group + ": " +
                      std::strerror(errno) + "; check that an interface with a multicast route exists.");
      }
    }
    return fd;
  }

  Expected<void> open() {
    if (auto p = ipv4_problem(network.bind); !p.empty()) return invalid("the bind address " + p + ".");
    if (!network.source.empty()) {
      if (auto p = ipv4_problem(network.source); !p.empty()) return invalid("the source address " + p + ".");
      ::inet_pton(AF_INET, network.source.c_str(), &source);
      filter_source = true;
    }
    if (!network.multicast_group.empty()) {
      if (auto p = multicast_group_problem(network.multicast_group); !p.empty()) {
        return invalid("the multicast group " + p + ".");
      }
    }
    auto l = open_socket(network.lidar_port, "the lidar");
    if (!l) return l.error();
    lidar = std::move(l.value());
    auto i = open_socket(network.imu_port, "the IMU");
    if (!i) return i.error();
    imu = std::move(i.value());
    return {};
  }

  void take(int fd, bool is_lidar, LidarStream& stream, const ReceiverCallbacks& callbacks) {
    for (;;) {
      const int count = batch.receive(fd);
      if (count <= 0) return;  // EAGAIN: all taken; other errors are transient for UDP
      const std::int64_t now = monotonic_ns();
      for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
        ++counters.datagrams;
        if (filter_source && batch.senders[i].sin_addr.s_addr != source.s_addr) {
          ++counters.other_source;
          continue;
        }
        if (batch.truncated(i)) {
          ++counters.oversized;
          continue;
        }
        last_packet_ns = now;
        if (!is_lidar) {
          stream.push_imu(batch.payload(i));
          continue;
        }
        const std::int64_t arrival = batch.arrival_ns(i);
        if (last_arrival_ns != 0 && arrival - last_arrival_ns > network.silence_timeout.count()) {
          stream.reset();
          ++counters.resumes;
          char message[96];
          std::snprintf(message, sizeof message, "packets resumed after %.1f s of silence",
                        static_cast<double>(arrival - last_arrival_ns) / 1e9);
          if (callbacks.note) callbacks.note(message);
        }
        last_arrival_ns = arrival;
        const PushResult result = stream.push_lidar(batch.payload(i), arrival);
        if (result.error != PacketError::none && !mismatch_noted && callbacks.note) {
          // Once: the user must learn that the metadata does not fit, not read it 640 times a second.
          const std::string problem = stream.mismatch_problem();
          if (!problem.empty()) {
            callbacks.note(problem);
            mismatch_noted = true;
          }
        }
      }
      if (static_cast<std::size_t>(count) < ReceiveBatch::size) return;
    }
  }
};

Expected<LiveReceiver> LiveReceiver::open(const NetworkConfig& network) {
  auto impl = std::make_unique<Impl>();
  impl->network = network;
  if (auto opened = impl->open(); !opened) return opened.error();
  return LiveReceiver(std::move(impl));
}

LiveReceiver::LiveReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
LiveReceiver::LiveReceiver(LiveReceiver&&) noexcept = default;
LiveReceiver& LiveReceiver::operator=(LiveReceiver&&) noexcept = default;
LiveReceiver::~LiveReceiver() = default;

void LiveReceiver::run(LidarStream& stream, int stop_fd, const ReceiverCallbacks& callbacks) {
  Impl& r = *impl_;
  const std::int64_t tick_ns = callbacks.tick ? callbacks.tick_period.count() : 0;
  std::int64_t next_tick_ns = monotonic_ns() + tick_ns;
  std::array<pollfd, 3> fds{pollfd{stop_fd, POLLIN, 0}, pollfd{r.lidar.get(), POLLIN, 0},
                            pollfd{r.imu.get(), POLLIN, 0}};
  for (;;) {
    for (auto& f : fds) f.revents = 0;
    timespec until_tick{};
    const timespec* timeout = nullptr;
    if (tick_ns > 0) {
      const std::int64_t left = std::max<std::int64_t>(0, next_tick_ns - monotonic_ns());
      until_tick = {static_cast<time_t>(left / 1'000'000'000), static_cast<long>(left % 1'000'000'000)};
      timeout = &until_tick;
    }
    ::ppoll(fds.data(), fds.size(), timeout, nullptr);
    if ((fds[0].revents & POLLIN) != 0) break;
    if ((fds[1].revents & POLLIN) != 0) r.take(r.lidar.get(), true, stream, callbacks);
    if ((fds[2].revents & POLLIN) != 0) r.take(r.imu.get(), false, stream, callbacks);
    if (tick_ns > 0 && monotonic_ns() >= next_tick_ns) {
      callbacks.tick();
      next_tick_ns = monotonic_ns() + tick_ns;
    }
  }
}

namespace {
std::uint16_t bound_port(int fd) {
  sockaddr_in local{};
  socklen_t length = sizeof local;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length);
  return ntohs(local.sin_port);
}
}  // namespace

std::uint16_t LiveReceiver::lidar_port() const noexcept { return bound_port(impl_->lidar.get()); }
std::uint16_t LiveReceiver::imu_port() const noexcept { return bound_port(impl_->imu.get()); }
int LiveReceiver::receive_buffer() const noexcept { return impl_->granted_buffer; }
const ReceiveCounters& LiveReceiver::counters() const noexcept { return impl_->counters; }
std::int64_t LiveReceiver::last_packet_ns() const noexcept { return impl_->last_packet_ns; }

}  // namespace sim::ouster
