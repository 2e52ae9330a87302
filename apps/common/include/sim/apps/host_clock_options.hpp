// SPDX-License-Identifier: Apache-2.0
// The option every program that reads the host's clock takes (sim::timing::HostClockWatch):
//   --ptp4l-socket PATH   ptp4l's management socket [/var/run/ptp/ptp4l, then /var/run/ptp4l]
// The same key in a --config file (ptp4l_socket; a relative path is relative to the file).
//
//   sim::timing::HostClockWatchOptions host;
//   sim::apps::add_host_clock_options(cli, host.clock);
//   ...parse...
//   sim::timing::HostClockWatch watch(host);  // reads it once a second, logs each change once
#pragma once

#include "sim/apps/command_line.hpp"
#include "sim/timing/host_clock.hpp"

namespace sim::apps {

// Adds --ptp4l-socket to `cli` (group "Clock"); a path too long for a Unix socket is a usage
// error (exit 2).
void add_host_clock_options(CommandLine& cli, sim::timing::HostClockOptions& options);

}  // namespace sim::apps
