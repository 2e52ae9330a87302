// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/host_clock_options.hpp"

#include <sys/un.h>

#include <string>

namespace sim::apps {

void add_host_clock_options(CommandLine& cli, sim::timing::HostClockOptions& options) {
  const auto socket_path_problem = [](const std::string& path) -> std::string {
    if (path.size() >= sizeof(sockaddr_un{}.sun_path)) {
      return "the ptp4l socket path is " + std::to_string(path.size()) +
             " bytes long; a Unix socket path has at most " +
             std::to_string(sizeof(sockaddr_un{}.sun_path) - 1);
    }
    return {};
  };
  cli.add_text("--ptp4l-socket", options.ptp4l_socket,
               "ptp4l's management socket, to read the host's PTP state "
               "[/var/run/ptp/ptp4l, then /var/run/ptp4l]",
               "PATH", socket_path_problem, "Clock");
  cli.add_path_option("ptp4l-socket");
}

}  // namespace sim::apps
