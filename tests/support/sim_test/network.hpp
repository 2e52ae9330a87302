// SPDX-License-Identifier: Apache-2.0
// A private network for the tests (and benches) that use real sockets: a new network namespace
// with its own loopback, so discovery and streaming never touch a real network and parallel tests
// never see each other's traffic.
#pragma once

#include <arpa/inet.h>
#include <net/if.h>
#include <net/route.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

namespace sim::testing {

enum class Multicast { off, on };

// The namespace and loopback of enter_private_network(); why not, when it cannot.
inline std::optional<std::string> enter_private_network_or_say_why(Multicast multicast) {
  if (unshare(CLONE_NEWNET) != 0) {
    return "cannot create a network namespace (needs root or CAP_SYS_ADMIN)";
  }
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return "cannot open a socket in the new network namespace";
  std::optional<std::string> failure;
  ifreq request{};
  std::snprintf(request.ifr_name, IFNAMSIZ, "lo");
  if (ioctl(fd, SIOCGIFFLAGS, &request) != 0) {
    failure = "cannot read the loopback interface in the new namespace";
  } else {
    request.ifr_flags = static_cast<short>(request.ifr_flags | IFF_UP |
                                           (multicast == Multicast::on ? IFF_MULTICAST : 0));
    if (ioctl(fd, SIOCSIFFLAGS, &request) != 0) failure = "cannot bring loopback up";
  }
  if (!failure && multicast == Multicast::on) {
    rtentry route{};
    auto* destination = reinterpret_cast<sockaddr_in*>(&route.rt_dst);
    auto* mask = reinterpret_cast<sockaddr_in*>(&route.rt_genmask);
    destination->sin_family = AF_INET;
    destination->sin_addr.s_addr = htonl(0xE0000000u);
    mask->sin_family = AF_INET;
    mask->sin_addr.s_addr = htonl(0xF0000000u);
    route.rt_flags = RTF_UP;
    char device[] = "lo";
    route.rt_dev = device;
    if (ioctl(fd, SIOCADDRT, &route) != 0) failure = "cannot route multicast through loopback";
  }
  close(fd);
  return failure;
}

// Moves the calling process into a new network namespace and brings its loopback up; with
// Multicast::on, 224.0.0.0/4 is routed through loopback too (DDS discovery needs it). Call it
// first thing in main(), before any thread exists: unshare() moves only the calling thread, and
// children inherit its namespace. Returns why it could not (tests skip with that sentence), except
// where a skip would hide them: with SIM_REQUIRE_PRIVATE_NETWORK set (scripts/test.sh sets it when
// it runs as root, as CI does) the program ends with that sentence and exit code 1.
inline std::optional<std::string> enter_private_network(Multicast multicast) {
  std::optional<std::string> failure = enter_private_network_or_say_why(multicast);
  if (failure && std::getenv("SIM_REQUIRE_PRIVATE_NETWORK") != nullptr) {
    std::fprintf(stderr, "%s; SIM_REQUIRE_PRIVATE_NETWORK is set, so this is a failure, not a skip\n",
                 failure->c_str());
    std::exit(1);
  }
  return failure;
}

}  // namespace sim::testing
