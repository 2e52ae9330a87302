// SPDX-License-Identifier: Apache-2.0
#include "sim/apps/host_clock_options.hpp"

#include <CLI/CLI.hpp>
#include <sys/un.h>

#include <string>

namespace sim::apps {

void add_host_clock_options(CommandLine& cli, sim::timing::HostClockOptions& options) {
  const auto socket_path = validator(
      [](const std::string& path) -> std::string {
        if (path.size() >= sizeof(sockaddr_un{}.sun_path)) {
          return "the ptp4l socket path is " + std::to_string(path.size()) +
                 " bytes long; a Unix socket path has at most " +
                 std::to_string(sizeof(sockaddr_un{}.sun_path) - 1);
        }
        return {};
      },
      "PATH");
  cli.app()
      .add_option("--ptp4l-socket", options.ptp4l_socket,
                  "ptp4l's management socket, to read the host's PTP state "
                  "[/var/run/ptp/ptp4l, then /var/run/ptp4l]")
      ->type_name("PATH")
      ->check(socket_path)
      ->group("Clock");
  cli.add_path_option("ptp4l-socket");
}

}  // namespace sim::apps
