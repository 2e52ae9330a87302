// SPDX-License-Identifier: Apache-2.0
// The host's own synchronisation, read by one shared piece for every driver and tool: ptp4l over
// its management socket (as `pmc -u -b 0` does, without a pmc process) and the kernel's adjtimex
// state. chrony's own socket is not read (yet): a host that chrony or ntpd synchronises shows as
// source host, locked, through the kernel's state.
//
//   sim::timing::HostClockWatch host({.ptp4l_socket = options.ptp4l_socket});  // a thread
//   ...
//   writer.set_clock(check.judge(sensor.latest(), host.latest(), sim::realtime_ns()));
//
// docs/time.md ("Host clock") says how each daemon's answer maps to the record.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/clock_status.hpp"
#include "sim/result.hpp"
#include "sim/timing/clock_poller.hpp"
#include "sim/timing/ptp_management.hpp"

namespace sim::timing {

struct HostClockOptions {
  // ptp4l's management socket; empty: /var/run/ptp/ptp4l, then /var/run/ptp4l (linuxptp after
  // and up to v4.4), each followed by its read-only twin (kPtp4lSockets). Every program that
  // reads it takes --ptp4l-socket PATH.
  std::string ptp4l_socket{};
  // The whole exchange with ptp4l: a socket that never answers costs this, and no more.
  std::chrono::milliseconds ptp4l_timeout{200};
  // ptp4l's domainNumber (it ignores requests for another domain); nullopt: domain 0 first, and
  // when that gets no answer, every other domain once (what answers is remembered per socket).
  std::optional<std::uint8_t> ptp_domain{};
};

// The default sockets, in the order they are tried (the next one when a socket is missing, has
// nobody listening, or may not be written): each read-write socket, then its read-only one
// (linuxptp 4's uds_ro_address, writable by every user; GET is all the reader sends).
inline constexpr const char* kPtp4lSockets[] = {"/var/run/ptp/ptp4l", "/var/run/ptp/ptp4lro",
                                                "/var/run/ptp4l", "/var/run/ptp4lro"};

// What ptp4l said (every part optional: a part it did not answer, or answered malformed, is
// missing, and `problem` says so).
struct Ptp4lAnswer {
  std::string socket;                   // the socket that answered
  std::uint8_t domain = 0;              // the domain it answered in
  std::uint8_t transport_specific = 0;  // 1: IEEE 802.1AS (gPTP)
  std::optional<ptp::DefaultDataSet> default_ds;
  std::optional<ptp::CurrentDataSet> current_ds;
  std::optional<ptp::ParentDataSet> parent_ds;
  std::optional<ptp::TimePropertiesDataSet> time_properties_ds;
  std::vector<ptp::PortDataSet> ports;  // one per port, by port number
  std::optional<ptp::TimeStatusNp> time_status;
  std::string problem;  // the first malformed or refused answer, one sentence; "" none
};

// What the kernel says of CLOCK_REALTIME (adjtimex with modes 0: no privileges needed).
struct KernelClock {
  bool read = false;            // adjtimex answered
  bool unsynchronised = false;  // TIME_ERROR or STA_UNSYNC: no daemon disciplines the clock
  std::int64_t max_error_us = 0;
  std::int32_t tai_offset_s = 0;  // TAI − UTC the daemon set; 0 never set
};

// One reading with what each daemon said.
struct HostClock {
  ClockStatus status;                 // the record (source, state, verdict, …)
  std::optional<Ptp4lAnswer> ptp4l;   // nullopt: no ptp4l answered
  std::string ptp4l_absent;           // why not: "no ptp4l socket at …", "ptp4l at … did not answer …"
  KernelClock kernel;
  std::string description;            // for people: "ptp slave of 00a069.fffe.0b552d, offset +3 µs"
};

// One reading of the host's clock, with bounded waits: never hangs on a silent daemon.
ClockStatus read_host_clock(const HostClockOptions& options);
HostClock read_host_clock_details(const HostClockOptions& options);

// The asking, apart: ptp4l's answer (or why there is none), and the kernel's state.
Expected<Ptp4lAnswer> ask_ptp4l(const HostClockOptions& options);
KernelClock read_kernel_clock() noexcept;
// Adds one parsed response to `answer` (a port's data set by its port number; a refusal as the
// problem sentence).
void fold_response(const ptp::Response& response, Ptp4lAnswer& answer);

// The record from what the daemons said (no I/O: the mapping documented in docs/time.md).
HostClock host_clock_from(std::optional<Ptp4lAnswer> ptp4l, std::string ptp4l_absent,
                          const KernelClock& kernel, std::int64_t now_realtime_ns);

struct HostClockWatchOptions {
  HostClockOptions clock{};
  std::chrono::milliseconds period = ClockPoller::kDefaultPeriod;
  // Where a change of the host's synchronisation goes, one line: "host clock: ptp slave of …,
  // offset +3 µs (was: no ptp4l), 2026-11-27 14:05:03 UTC". Empty: stderr.
  std::function<void(const std::string& line)> log{};
};

// Reads the host clock about once a second on its own thread (a ClockPoller), off every frame
// path, and logs each change of its synchronisation once.
class HostClockWatch {
 public:
  explicit HostClockWatch(HostClockWatchOptions options = {});
  ~HostClockWatch();  // stops promptly: at most one bounded reading in progress
  HostClockWatch(const HostClockWatch&) = delete;
  HostClockWatch& operator=(const HostClockWatch&) = delete;

  // The last reading (a default ClockStatus before the first). Never waits.
  ClockStatus latest() const;
  // The last reading with what each daemon said.
  HostClock latest_details() const;
  // The poller (readings(), wait_for_readings(), poll_now()).
  ClockPoller& poller() noexcept { return *poller_; }

 private:
  struct Shared;
  std::shared_ptr<Shared> shared_;
  std::unique_ptr<ClockPoller> poller_;  // last: its thread uses shared_
};

}  // namespace sim::timing
