// SPDX-License-Identifier: Apache-2.0
#include "sim/lidar/udp_receiver.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "sim/clock.hpp"
#include "sim/lidar/unique_fd.hpp"

namespace sim::lidar {
namespace {

// Sockets one receiver may have (Velodyne: data and position; Ouster: lidar and IMU).
constexpr std::size_t max_sockets = 4;

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }
Error failed(std::string message) { return Error{ErrorCode::system_error, std::move(message)}; }

// An IPv4 or IPv6 address as the socket calls take it.
struct IpAddress {
  int family = AF_INET;
  in_addr v4{};
  in6_addr v6{};
  std::uint32_t scope_id = 0;  // the interface of a link-local IPv6 address ("fe80::1%eth0")
};

// The interface index of an IPv6 zone ("eth0" or "2"); nullopt for an interface this host lacks.
std::optional<std::uint32_t> scope_of(const std::string& zone) {
  if (const unsigned index = ::if_nametoindex(zone.c_str()); index != 0) return index;
  if (!zone.empty() && zone.find_first_not_of("0123456789") == std::string::npos && zone.size() < 10) {
    return static_cast<std::uint32_t>(std::stoul(zone));
  }
  return std::nullopt;
}

std::optional<IpAddress> parse_address(const std::string& text, IpVersions versions) {
  IpAddress address;
  if (::inet_pton(AF_INET, text.c_str(), &address.v4) == 1) return address;
  if (versions != IpVersions::v4_and_v6) return std::nullopt;
  const std::size_t percent = text.find('%');
  if (percent != std::string::npos) {  // a link-local address with its zone, as asio took it
    const auto scope = scope_of(text.substr(percent + 1));
    if (!scope) return std::nullopt;
    address.scope_id = *scope;
  }
  if (::inet_pton(AF_INET6, text.substr(0, percent).c_str(), &address.v6) == 1) {
    address.family = AF_INET6;
    if (IN6_IS_ADDR_V4MAPPED(&address.v6)) {  // ::ffff:a.b.c.d is the IPv4 sender a.b.c.d
      address.family = AF_INET;
      std::memcpy(&address.v4, address.v6.s6_addr + 12, sizeof address.v4);
    }
    return address;
  }
  return std::nullopt;
}

bool is_multicast(const IpAddress& a) {
  if (a.family == AF_INET) return (ntohl(a.v4.s_addr) >> 28) == 0xE;
  return IN6_IS_ADDR_MULTICAST(&a.v6);
}

// Whether a datagram's sender is `source`; a dual-stack socket reports IPv4 senders as
// ::ffff:a.b.c.d, and --source is written as IPv4.
bool same_address(const sockaddr_storage& sender, const IpAddress& source) noexcept {
  if (sender.ss_family == AF_INET) {
    return source.family == AF_INET &&
           reinterpret_cast<const sockaddr_in&>(sender).sin_addr.s_addr == source.v4.s_addr;
  }
  if (sender.ss_family != AF_INET6) return false;
  const in6_addr& a = reinterpret_cast<const sockaddr_in6&>(sender).sin6_addr;
  if (IN6_IS_ADDR_V4MAPPED(&a)) {
    return source.family == AF_INET && std::memcmp(a.s6_addr + 12, &source.v4, sizeof source.v4) == 0;
  }
  return source.family == AF_INET6 && std::memcmp(&a, &source.v6, sizeof a) == 0;
}

// The sender's address as an IpAddress (an IPv4 sender of a dual-stack socket as IPv4).
IpAddress sender_address(const sockaddr_storage& sender) noexcept {
  IpAddress address;
  if (sender.ss_family == AF_INET) {
    address.v4 = reinterpret_cast<const sockaddr_in&>(sender).sin_addr;
  } else if (sender.ss_family == AF_INET6) {
    const in6_addr& a = reinterpret_cast<const sockaddr_in6&>(sender).sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&a)) {
      std::memcpy(&address.v4, a.s6_addr + 12, sizeof address.v4);
    } else {
      address.family = AF_INET6;
      address.v6 = a;
    }
  }
  return address;
}

bool is_unspecified(const IpAddress& ip) noexcept {
  return ip.family == AF_INET ? ip.v4.s_addr == htonl(INADDR_ANY) : IN6_IS_ADDR_UNSPECIFIED(&ip.v6);
}

// The index of the interface that holds `local` (an IPv6 --bind address); 0 when none does.
unsigned interface_of(const IpAddress& local) {
  if (local.scope_id != 0) return local.scope_id;
  ifaddrs* all = nullptr;
  if (::getifaddrs(&all) != 0) return 0;
  unsigned index = 0;
  for (const ifaddrs* i = all; i != nullptr && index == 0; i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET6) continue;
    if (std::memcmp(&reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr, &local.v6, sizeof local.v6) == 0) {
      index = ::if_nametoindex(i->ifa_name);
    }
  }
  ::freeifaddrs(all);
  return index;
}

socklen_t socket_address(const IpAddress& ip, std::uint16_t port, sockaddr_storage& out) {
  out = {};
  if (ip.family == AF_INET) {
    auto& a = reinterpret_cast<sockaddr_in&>(out);
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr = ip.v4;
    return sizeof a;
  }
  auto& a = reinterpret_cast<sockaddr_in6&>(out);
  a.sin6_family = AF_INET6;
  a.sin6_port = htons(port);
  a.sin6_addr = ip.v6;
  a.sin6_scope_id = ip.scope_id;
  return sizeof a;
}

// A revolution arrives in bursts; at 3600 packets/s a default 200 KiB buffer holds ~50 ms of
// data, so a short stall of this process would drop packets. Returns what the kernel granted.
int set_receive_buffer(int fd, int wanted) {
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &wanted, sizeof wanted);
  int granted = 0;
  socklen_t length = sizeof granted;
  ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &granted, &length);
  if (granted < wanted) {  // root may exceed net.core.rmem_max
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &wanted, sizeof wanted);
    ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &granted, &length);
  }
  return granted;
}

#ifndef IPV6_MULTICAST_ALL
#define IPV6_MULTICAST_ALL 29  // Linux 4.20; older C libraries lack the name
#endif

// Joins the group on the interface of `local` (--bind: "on this NIC"; the wildcard: the one the
// routing table picks) and receives only the groups this socket joined: Linux's default
// (IP_MULTICAST_ALL 1) hands a socket bound to the wildcard every group any socket of the host
// joined on its port, so two drivers on one port with two groups would each get both sensors.
bool join_group(int fd, const IpAddress& group, const IpAddress& local) {
  const int off = 0;
  if (group.family == AF_INET) {
    ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_ALL, &off, sizeof off);
    ip_mreq membership{};
    membership.imr_multiaddr = group.v4;
    membership.imr_interface = local.family == AF_INET ? local.v4 : in_addr{htonl(INADDR_ANY)};
    return ::setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) == 0;
  }
  ::setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_ALL, &off, sizeof off);  // fails before 4.20: harmless
  ipv6_mreq membership{};
  membership.ipv6mr_multiaddr = group.v6;
  membership.ipv6mr_interface = group.scope_id != 0 ? group.scope_id : is_unspecified(local) ? 0 : interface_of(local);
  return ::setsockopt(fd, IPPROTO_IPV6, IPV6_JOIN_GROUP, &membership, sizeof membership) == 0;
}

timespec as_timespec(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

// Room for one recvmmsg, allocated once: payloads, sender addresses and the kernel's stamps.
class ReceiveBatch {
 public:
  ReceiveBatch(std::size_t count, std::size_t datagram_size)
      : datagram_size_(datagram_size), payloads_(count * datagram_size), senders_(count),
        vectors_(count), controls_(count), headers_(count) {}

  std::size_t size() const noexcept { return headers_.size(); }

  // Takes up to size() queued datagrams without waiting: how many (0: none, or an error).
  std::size_t receive(int fd) noexcept {
    for (std::size_t i = 0; i < size(); ++i) {  // recvmmsg overwrites the lengths
      vectors_[i] = {payloads_.data() + i * datagram_size_, datagram_size_};
      msghdr& h = headers_[i].msg_hdr;
      h = {};
      h.msg_name = &senders_[i];
      h.msg_namelen = sizeof(sockaddr_storage);
      h.msg_iov = &vectors_[i];
      h.msg_iovlen = 1;
      h.msg_control = controls_[i].data();
      h.msg_controllen = controls_[i].size();
      headers_[i].msg_len = 0;
    }
    const int count = ::recvmmsg(fd, headers_.data(), static_cast<unsigned>(size()), MSG_DONTWAIT, nullptr);
    return count > 0 ? static_cast<std::size_t>(count) : 0;
  }

  const sockaddr_storage& sender(std::size_t i) const noexcept { return senders_[i]; }

  Datagram datagram(std::size_t i, std::size_t socket, std::int64_t taken_ns) noexcept {
    Datagram d;
    d.socket = socket;
    d.payload = {payloads_.data() + i * datagram_size_, headers_[i].msg_len};
    d.truncated = (headers_[i].msg_hdr.msg_flags & MSG_TRUNC) != 0;
    d.arrival_ns = arrival_ns(i);
    d.taken_ns = taken_ns;
    d.sender = &senders_[i];
    return d;
  }

 private:
  // CLOCK_REALTIME of the datagram's arrival, from the kernel; now if it gave none.
  std::int64_t arrival_ns(std::size_t i) noexcept {
    msghdr& h = headers_[i].msg_hdr;
    for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec t;
        std::memcpy(&t, CMSG_DATA(c), sizeof t);
        return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
      }
    }
    return realtime_ns();
  }

  std::size_t datagram_size_;
  std::vector<std::uint8_t> payloads_;
  std::vector<sockaddr_storage> senders_;
  std::vector<iovec> vectors_;
  std::vector<std::array<char, CMSG_SPACE(sizeof(timespec))>> controls_;
  std::vector<mmsghdr> headers_;
};

}  // namespace

std::string address_problem(const std::string& address, IpVersions versions) {
  if (parse_address(address, versions)) return {};
  const char* kind = versions == IpVersions::v4 ? "an IPv4" : "an IP";
  return "'" + address + "' is not " + kind + " address (e.g. 192.168.1.201)";
}

std::string multicast_group_problem(const std::string& group, IpVersions versions) {
  const auto address = parse_address(group, versions);
  if (address && is_multicast(*address)) return {};
  const char* kind = versions == IpVersions::v4 ? "an IPv4 multicast" : "a multicast";
  return "'" + group + "' is not " + kind + " group address (e.g. 239.255.0.1)";
}

std::string describe_problems(const ReceiveCounters& c) {
  std::string text;
  if (c.other_source != 0) text += " other-source " + std::to_string(c.other_source);
  if (c.other_senders != 0) text += " other-senders " + std::to_string(c.other_senders);
  if (c.unrecognised != 0) text += " unrecognised " + std::to_string(c.unrecognised);
  if (c.oversized != 0) text += " oversized " + std::to_string(c.oversized);
  return text;
}

std::string address_text(const sockaddr_storage& address) {
  char text[INET6_ADDRSTRLEN] = "?";
  if (address.ss_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in&>(address).sin_addr, text, sizeof text);
  } else if (address.ss_family == AF_INET6) {
    const in6_addr& a = reinterpret_cast<const sockaddr_in6&>(address).sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&a)) {
      ::inet_ntop(AF_INET, a.s6_addr + 12, text, sizeof text);
    } else {
      ::inet_ntop(AF_INET6, &a, text, sizeof text);
    }
  }
  return text;
}

struct UdpReceiver::Impl {
  Impl(UdpListen l, std::size_t datagram_size, std::size_t batch_size)
      : listen(std::move(l)), batch(batch_size, datagram_size) {
    accepted.reserve(batch_size);
  }

  UdpListen listen;
  std::optional<IpAddress> source;
  std::vector<UniqueFd> sockets;
  int granted_buffer = 0;
  ReceiveBatch batch;
  std::vector<Datagram> accepted;  // of a batch, from accepted senders: one handler call each batch
  ReceiveCounters counters;
  const ReceiverCallbacks* callbacks = nullptr;  // during run()
  std::int64_t last_arrival_ns = 0;              // kernel stamp of the last data packet
  std::optional<IpAddress> first_sender;         // without --source: the first one heard

  Expected<void> open(std::span<const UdpPort> ports) {
    const auto local_ip = parse_address(listen.bind, listen.versions);
    if (!local_ip) {
      return invalid("the bind address " + address_problem(listen.bind, listen.versions) +
                     "; give the local address to receive on, or 0.0.0.0 for all.");
    }
    if (!listen.source.empty()) {
      source = parse_address(listen.source, listen.versions);
      if (!source) {
        return invalid("the source address " + address_problem(listen.source, listen.versions) +
                       "; give the sensor's address.");
      }
    }
    std::optional<IpAddress> group;
    if (!listen.multicast_group.empty()) {
      if (auto problem = multicast_group_problem(listen.multicast_group, listen.versions); !problem.empty()) {
        return invalid("the multicast group " + problem + "; give the group the sensor sends to.");
      }
      group = parse_address(listen.multicast_group, listen.versions);
    }
    if (ports.size() > max_sockets) return invalid("a receiver has at most 4 sockets.");
    for (const UdpPort& port : ports) {
      auto socket = open_socket(*local_ip, port, group);
      if (!socket) return socket.error();
      sockets.push_back(std::move(socket.value()));
    }
    return {};
  }

  // A bound socket with arrival stamps, the receive buffer asked for and the group joined.
  Expected<UniqueFd> open_socket(const IpAddress& local_ip, const UdpPort& port, const std::optional<IpAddress>& group) {
    UniqueFd fd(::socket(local_ip.family, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    if (fd.get() < 0) return failed(std::string("cannot open a UDP socket: ") + std::strerror(errno) + ".");
    const int on = 1;
    // Several receivers of one multicast group must share the port; a unicast port must not be
    // shared, so two drivers on one port fail loudly instead of splitting the packets.
    if (group) ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    ::setsockopt(fd.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
    const int granted = set_receive_buffer(fd.get(), listen.receive_buffer);
    if (sockets.empty()) granted_buffer = granted;
    // A group's datagrams are addressed to the group, never to a unicast --bind address: the
    // socket takes the wildcard and --bind chooses the membership's interface instead.
    IpAddress bound = local_ip;
    if (group) {
      bound.v4.s_addr = htonl(INADDR_ANY);
      bound.v6 = in6addr_any;
      bound.scope_id = 0;
    }
    sockaddr_storage local{};
    const socklen_t length = socket_address(bound, port.port, local);
    if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&local), length) != 0) {
      const int error = errno;
      const std::string number = std::to_string(port.port);
      if (error == EADDRINUSE) {
        return failed(port.what + " port " + number + " on " + listen.bind +
                      " is already in use by another process (another driver?); stop it or choose "
                      "another " + port.option + ".");
      }
      return failed("cannot bind to " + listen.bind + ":" + number + ": " + std::strerror(error) +
                    "; check " + listen.bind_option + " and " + port.option + ".");
    }
    if (group && !join_group(fd.get(), *group, local_ip)) {
      const std::string where = is_unspecified(local_ip) ? "" : " on the interface of " + listen.bind;
      return failed("cannot join multicast group " + listen.multicast_group + where + ": " +
                    std::strerror(errno) + "; check that an interface with a multicast route exists" +
                    (where.empty() ? "." : " and that " + listen.bind_option + " is an address of this host."));
    }
    return fd;
  }

  // Sleeps until a datagram arrives, a stop request, or the next tick (-1: no tick). A nap
  // watches only the stop descriptor (packets wait in the socket buffer) and then has every
  // socket looked at.
  static void wait(std::span<pollfd> fds, std::int64_t nap_ns, std::int64_t next_tick_ns) {
    for (pollfd& f : fds) f.revents = 0;
    if (nap_ns > 0) {
      const timespec nap = as_timespec(nap_ns);
      ::ppoll(fds.data(), 1, &nap, nullptr);
      for (pollfd& f : fds.subspan(1)) f.revents = POLLIN;
      return;
    }
    timespec until_tick{};
    const timespec* timeout = nullptr;
    if (next_tick_ns >= 0) {
      until_tick = as_timespec(std::max<std::int64_t>(0, next_tick_ns - monotonic_ns()));
      timeout = &until_tick;
    }
    ::ppoll(fds.data(), fds.size(), timeout, nullptr);
  }

  // Takes the queued datagrams of every socket that woke the loop: how many, or nullopt when
  // the handler ended the run.
  std::optional<std::size_t> take_ready(std::span<const pollfd> fds, DatagramHandler& handler) {
    std::size_t taken = 0;
    for (std::size_t s = 0; s < sockets.size(); ++s) {
      // POLLERR too: the receive takes the socket's pending error (a queued ICMP error), which
      // would otherwise wake the loop again at once.
      if (fds[s + 1].revents == 0) continue;
      if (!take(s, handler, taken)) return std::nullopt;
    }
    return taken;
  }

  // Without --source every sender is taken: a second one is two sensors on one port (or group),
  // whose packets the family would decode as one sensor's. Counted, and said once.
  void count_sender(const sockaddr_storage& sender) {
    if (!first_sender) {
      first_sender = sender_address(sender);
      return;
    }
    if (same_address(sender, *first_sender)) return;
    if (counters.other_senders++ != 0) return;
    sockaddr_storage first{};
    socket_address(*first_sender, 0, first);
    const ReceiverCallbacks* c = callbacks;
    if (c != nullptr && c->note) {
      c->note("warning: datagrams from " + address_text(sender) + " arrive besides those from " +
              address_text(first) + ": two sensors on one port are decoded as one; give each its own "
              "port (or multicast group) and driver, or choose one with " + listen.source_option);
    }
  }

  bool take(std::size_t socket, DatagramHandler& handler, std::size_t& taken) {
    for (;;) {
      // 0: all taken (EAGAIN). Other errors on an unconnected UDP socket are transient (e.g. an
      // ICMP error queued for it); the next wake-up tries again.
      const std::size_t count = batch.receive(sockets[socket].get());
      if (count == 0) return true;
      taken += count;
      const std::int64_t now = monotonic_ns();
      accepted.clear();
      for (std::size_t i = 0; i < count; ++i) {
        ++counters.datagrams;
        if (source && !same_address(batch.sender(i), *source)) {
          ++counters.other_source;
          continue;
        }
        if (!source) count_sender(batch.sender(i));
        accepted.push_back(batch.datagram(i, socket, now));
      }
      // One call into the family a batch, not one a datagram.
      if (!accepted.empty() && !handler.on_datagrams(accepted)) return false;
      if (count < batch.size()) return true;
    }
  }
};

Expected<UdpReceiver> UdpReceiver::open(const UdpListen& listen, std::span<const UdpPort> ports,
                                        std::size_t datagram_size, std::size_t batch_size) {
  auto impl = std::make_unique<Impl>(listen, datagram_size, batch_size);
  if (auto opened = impl->open(ports); !opened) return opened.error();
  return UdpReceiver(std::move(impl));
}

UdpReceiver::UdpReceiver(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
UdpReceiver::UdpReceiver(UdpReceiver&&) noexcept = default;
UdpReceiver& UdpReceiver::operator=(UdpReceiver&&) noexcept = default;
UdpReceiver::~UdpReceiver() = default;

// The loop is ppoll on the sockets rather than an event library's reactor: a reactor watches
// the sockets even with no read pending, so every datagram would wake a napping receiver.
void UdpReceiver::run(int stop_fd, DatagramHandler& handler, const ReceiverCallbacks& callbacks) {
  Impl& r = *impl_;
  r.callbacks = &callbacks;
  const std::int64_t tick_ns = callbacks.tick ? callbacks.tick_period.count() : 0;
  std::int64_t next_tick_ns = monotonic_ns() + tick_ns;
  std::array<pollfd, 1 + max_sockets> all{};
  all[0] = pollfd{stop_fd, POLLIN, 0};
  for (std::size_t s = 0; s < r.sockets.size(); ++s) all[s + 1] = pollfd{r.sockets[s].get(), POLLIN, 0};
  const std::span<pollfd> fds(all.data(), 1 + r.sockets.size());
  std::size_t last_take = 0;
  for (;;) {
    // Never a nap after an empty take: the sensor may have stopped; then wait until it sends.
    Impl::wait(fds, last_take > 0 ? handler.nap_ns() : 0, tick_ns > 0 ? next_tick_ns : -1);
    if ((fds[0].revents & POLLIN) != 0) break;
    const auto taken = r.take_ready(fds, handler);
    if (!taken) break;
    last_take = *taken;
    if (tick_ns > 0 && monotonic_ns() >= next_tick_ns) {
      callbacks.tick();
      next_tick_ns = monotonic_ns() + tick_ns;
    }
  }
  r.callbacks = nullptr;
}

bool UdpReceiver::resumed_after_silence(std::int64_t arrival_ns) {
  Impl& r = *impl_;
  const std::int64_t silence_ns = r.last_arrival_ns != 0 ? arrival_ns - r.last_arrival_ns : 0;
  r.last_arrival_ns = arrival_ns;
  if (silence_ns <= r.listen.silence_timeout.count()) return false;
  ++r.counters.resumes;
  char message[96];
  std::snprintf(message, sizeof message, "packets resumed after %.1f s of silence",
                static_cast<double>(silence_ns) / 1e9);
  note(message);
  return true;
}

void UdpReceiver::note(std::string_view message) const {
  const ReceiverCallbacks* callbacks = impl_->callbacks;
  if (callbacks != nullptr && callbacks->note) callbacks->note(message);
}

std::uint16_t UdpReceiver::port(std::size_t socket) const noexcept {
  if (socket >= impl_->sockets.size()) return 0;
  sockaddr_storage local{};
  socklen_t length = sizeof local;
  if (::getsockname(impl_->sockets[socket].get(), reinterpret_cast<sockaddr*>(&local), &length) != 0) return 0;
  if (local.ss_family == AF_INET6) return ntohs(reinterpret_cast<const sockaddr_in6&>(local).sin6_port);
  return ntohs(reinterpret_cast<const sockaddr_in&>(local).sin_port);
}

std::string UdpReceiver::local_address(std::size_t socket) const {
  sockaddr_storage local{};
  socklen_t length = sizeof local;
  if (socket < impl_->sockets.size()) {
    ::getsockname(impl_->sockets[socket].get(), reinterpret_cast<sockaddr*>(&local), &length);
  }
  return address_text(local) + ":" + std::to_string(port(socket));
}

int UdpReceiver::receive_buffer() const noexcept { return impl_->granted_buffer; }
const ReceiveCounters& UdpReceiver::counters() const noexcept { return impl_->counters; }
ReceiveCounters& UdpReceiver::counters() noexcept { return impl_->counters; }

}  // namespace sim::lidar
