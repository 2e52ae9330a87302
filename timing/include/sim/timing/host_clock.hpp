// SPDX-License-Identifier: Apache-2.0
// The host's own synchronisation, read by one shared piece for every driver and tool: ptp4l over
// its management socket (as pmc does), the kernel's adjtimex state, and chrony where it answers.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "sim/clock_status.hpp"
#include "sim/result.hpp"

namespace sim::timing {

struct HostClockOptions {
  // ptp4l's management socket; empty: /var/run/ptp/ptp4l, then /var/run/ptp4l (linuxptp before
  // and after v4.4). Every program that reads it takes --ptp4l-socket PATH.
  std::string ptp4l_socket{};
};

// One reading of the host's clock (source host or ptp/gptp, state, offset from master, path
// delay, grandmaster, UTC offset), with bounded waits: never hangs on a silent daemon.
ClockStatus read_host_clock(const HostClockOptions& options);

}  // namespace sim::timing
