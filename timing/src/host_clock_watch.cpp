// SPDX-License-Identifier: Apache-2.0
// What the daemons said, as the clock record and one line for people; and the watch that reads
// it once a second. The mapping is docs/time.md's "Host clock" table.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <mutex>
#include <utility>

#include "sim/timing/host_clock.hpp"

namespace sim::timing {
namespace {

using ptp::PortState;

constexpr std::int64_t kAbsurdOffsetNs = 1'000'000'000;  // a locked servo never strays a second

// The port that says most about the host's clock: a slave port first (a boundary clock's other
// ports are masters), then one on its way to slave, then a master, then the rest.
int rank(PortState state) noexcept {
  switch (state) {
    case PortState::slave: return 0;
    case PortState::uncalibrated: return 1;
    case PortState::grand_master:
    case PortState::master: return 2;
    case PortState::passive: return 3;
    case PortState::pre_master: return 4;
    case PortState::listening: return 5;
    case PortState::initializing: return 6;
    case PortState::faulty: return 7;
    case PortState::disabled: return 8;
  }
  return 9;
}

ClockState state_of(PortState port) noexcept {
  switch (port) {
    case PortState::slave:  // ptp4l moves to SLAVE only once its servo locked
    case PortState::master:
    case PortState::grand_master:  // the host is the domain's time: locked to itself
      return ClockState::locked;
    case PortState::uncalibrated:
    case PortState::listening:
    case PortState::pre_master:
    case PortState::initializing:
    case PortState::passive:
      return ClockState::acquiring;
    case PortState::faulty:
    case PortState::disabled:
      return ClockState::holdover;
  }
  return ClockState::unknown;
}

// "+87 ns", "+3 µs", "-1.5 ms", "+2.0 s".
std::string offset_text(std::int64_t ns) {
  char text[48];
  const char sign = ns < 0 ? '-' : '+';
  const double magnitude = ns < 0 ? -static_cast<double>(ns) : static_cast<double>(ns);
  if (magnitude < 1e3) {
    std::snprintf(text, sizeof text, "%c%.0f ns", sign, magnitude);
  } else if (magnitude < 1e6) {
    std::snprintf(text, sizeof text, "%c%.0f µs", sign, magnitude / 1e3);
  } else if (magnitude < 1e9) {
    std::snprintf(text, sizeof text, "%c%.1f ms", sign, magnitude / 1e6);
  } else {
    std::snprintf(text, sizeof text, "%c%.1f s", sign, magnitude / 1e9);
  }
  return text;
}

std::string fit(std::string sentence) {
  if (sentence.size() > ClockStatus::kMaxProblem) {
    sentence.resize(ClockStatus::kMaxProblem);
    // Never cut a UTF-8 sequence in two: drop continuation bytes and their lead byte.
    while (!sentence.empty() && (static_cast<unsigned char>(sentence.back()) & 0xC0) == 0x80) {
      sentence.pop_back();
    }
    if (!sentence.empty() && (static_cast<unsigned char>(sentence.back()) & 0x80) != 0) {
      sentence.pop_back();
    }
  }
  return sentence;
}

std::string problem_of(PortState port, const std::string& gm) {
  switch (port) {
    case PortState::uncalibrated:
      return "ptp4l's port is UNCALIBRATED: its servo has not locked to grandmaster " + gm +
             " (or ptp4l runs with free_running); stamps may be off until it does";
    case PortState::listening:
    case PortState::initializing:
    case PortState::pre_master:
      return std::string("ptp4l's port is ") + ptp::to_string(port) +
             ": it hears no master yet; check the network and the grandmaster";
    case PortState::passive:
      return "ptp4l's port is PASSIVE: it does not synchronise through this port; check the "
             "other ports";
    case PortState::faulty:
    case PortState::disabled:
      return std::string("ptp4l's port is ") + ptp::to_string(port) +
             ": the host's clock is no longer synchronised; check ptp4l's log";
    default:
      return {};
  }
}

void map_ptp4l(const Ptp4lAnswer& a, HostClock& h) {
  ClockStatus& s = h.status;
  const bool gptp = a.transport_specific == 1;
  s.source = gptp ? ClockSource::gptp : ClockSource::ptp;
  s.ptp_domain = a.default_ds ? a.default_ds->domain : a.domain;
  if (a.parent_ds) {
    s.grandmaster = ptp::format_clock_identity(a.parent_ds->grandmaster);
  } else if (a.time_status) {
    s.grandmaster = ptp::format_clock_identity(a.time_status->gm_identity);
  }
  if (a.current_ds) {
    s.offset_from_master_ns = a.current_ds->offset_from_master_ns;
    s.path_delay_ns = a.current_ds->mean_path_delay_ns;
  } else if (a.time_status) {
    s.offset_from_master_ns = a.time_status->master_offset_ns;
  }
  if (a.time_properties_ds) {
    if (a.time_properties_ds->utc_offset_valid) {
      s.utc_offset_s = a.time_properties_ds->current_utc_offset_s;
    }
    s.ptp_timescale = a.time_properties_ds->ptp_timescale;
  }
  const std::string name = gptp ? "gptp" : "ptp";
  const std::string gm = s.grandmaster.empty() ? "unknown" : s.grandmaster;
  const auto best = std::min_element(a.ports.begin(), a.ports.end(), [](const auto& x, const auto& y) {
    return rank(x.state) < rank(y.state);
  });
  std::string problem = a.problem;
  if (best == a.ports.end()) {
    s.state = ClockState::unknown;
    h.description = name + ", port state not answered";
    if (problem.empty()) problem = "ptp4l did not say its port state; check linuxptp's version";
  } else {
    const PortState port = best->state;
    s.state = state_of(port);
    if (port == PortState::slave) {
      h.description = name + " slave of " + gm;
    } else if (port == PortState::master || port == PortState::grand_master) {
      h.description = name + " master: this host is the grandmaster (" + gm + ")";
    } else if (port == PortState::uncalibrated) {
      h.description = name + " UNCALIBRATED, grandmaster " + gm;
    } else {
      // ptp4l keeps its last parent and offset after losing its master: stale, not reported.
      h.description = name + " " + ptp::to_string(port) + ", last grandmaster " + gm;
      s.offset_from_master_ns.reset();
      s.path_delay_ns.reset();
    }
    if (problem.empty()) problem = problem_of(port, gm);
    if (problem.empty() && s.offset_from_master_ns &&
        (*s.offset_from_master_ns > kAbsurdOffsetNs || *s.offset_from_master_ns < -kAbsurdOffsetNs)) {
      problem = "ptp4l says " + std::string(ptp::to_string(port)) + " yet reports an offset of " +
                offset_text(*s.offset_from_master_ns) +
                " from its master; check ptp4l and its grandmaster";
    }
  }
  const bool master = best != a.ports.end() &&
                      (best->state == PortState::master || best->state == PortState::grand_master);
  if (s.offset_from_master_ns && !master) {
    h.description += ", offset " + offset_text(*s.offset_from_master_ns);
  }
  s.problem = fit(problem);
  s.verdict = s.problem.empty() ? ClockVerdict::ok : ClockVerdict::warn;
}

void map_kernel(HostClock& h) {
  ClockStatus& s = h.status;
  s.source = ClockSource::host;
  const KernelClock& k = h.kernel;
  if (!k.read) {
    s.state = ClockState::unknown;
    s.verdict = ClockVerdict::unknown;
    h.description = "no ptp4l; the kernel's clock state cannot be read";
    return;
  }
  if (k.tai_offset_s > 0) s.utc_offset_s = k.tai_offset_s;
  if (k.unsynchronised) {
    s.state = ClockState::free_running;
    s.verdict = ClockVerdict::warn;
    s.problem = "nothing synchronises this host's clock (no ptp4l, and the kernel says "
                "unsynchronised): its stamps cannot be compared with another host's; run chrony "
                "or ptp4l";
    h.description = "no ptp4l; the kernel says unsynchronised (nothing disciplines this clock)";
    return;
  }
  s.state = ClockState::locked;
  s.verdict = ClockVerdict::ok;
  char text[96];
  std::snprintf(text, sizeof text, ", max error %.1f ms",
                static_cast<double>(k.max_error_us) / 1e3);
  h.description = "no ptp4l; the kernel says synchronised (chrony or ntpd)" + std::string(text);
}

std::string utc_text(std::int64_t realtime_ns) {
  const std::time_t seconds = static_cast<std::time_t>(realtime_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[40];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &utc);
  return text;
}

}  // namespace

HostClock host_clock_from(std::optional<Ptp4lAnswer> ptp4l, std::string ptp4l_absent,
                          const KernelClock& kernel, std::int64_t now_realtime_ns) {
  HostClock h;
  h.kernel = kernel;
  h.status.reported_ns = now_realtime_ns;
  h.ptp4l_absent = std::move(ptp4l_absent);
  if (ptp4l) {
    map_ptp4l(*ptp4l, h);
  } else {
    map_kernel(h);
  }
  h.ptp4l = std::move(ptp4l);
  return h;
}

struct HostClockWatch::Shared {
  HostClockOptions options;
  std::function<void(const std::string&)> log;
  mutable std::mutex mutex;
  HostClock latest;                  // guarded by mutex
  std::string previous_description;  // the poller's thread only
  std::string current_description;   // the poller's thread only
};

HostClockWatch::HostClockWatch(HostClockWatchOptions options)
    : shared_(std::make_shared<Shared>()) {
  shared_->options = std::move(options.clock);
  shared_->log = std::move(options.log);
  if (!shared_->log) {
    shared_->log = [](const std::string& line) { std::cerr << line << '\n' << std::flush; };
  }
  auto shared = shared_;
  poller_ = std::make_unique<ClockPoller>(
      [shared] {
        HostClock reading = read_host_clock_details(shared->options);
        shared->previous_description = std::exchange(shared->current_description, reading.description);
        ClockStatus status = reading.status;
        std::lock_guard lock(shared->mutex);
        shared->latest = std::move(reading);
        return status;
      },
      options.period,
      [shared](const ClockStatus& previous, const ClockStatus& current) {
        std::string line = "host clock: " + shared->current_description;
        if (previous.reported_ns != 0) line += " (was: " + shared->previous_description + ")";
        shared->log(line + ", " + utc_text(current.reported_ns));
      });
}

HostClockWatch::~HostClockWatch() { poller_.reset(); }

ClockStatus HostClockWatch::latest() const { return poller_->latest(); }

HostClock HostClockWatch::latest_details() const {
  std::lock_guard lock(shared_->mutex);
  return shared_->latest;
}

}  // namespace sim::timing
