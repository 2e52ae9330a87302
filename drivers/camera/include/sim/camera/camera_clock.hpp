// SPDX-License-Identifier: Apache-2.0
// A camera stream's clock as data (sim::ClockStatus): which clock its stamps are in and what the
// camera says of its synchronisation. V4L2 drivers stamp buffers with the host's monotonic clock
// (or say they cannot: UNKNOWN, COPY); GigE Vision cameras with their own clock, which PTP may
// discipline (the GenICam PTP features, read about once a second off the frame path).
//
// Only the reported fields are set here (and a verdict of warn with its sentence when the
// report alone shows a problem); the measured fields and the final verdict are the clock
// check's, which compares each frame's stamp with its arrival on this host.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sim/clock_status.hpp"
#include "sim/timing/clock_check.hpp"
#include "sim/timing/reported_clock.hpp"

namespace sim::camera {

// The clock a capture last reported, for the clock check on another thread.
using timing::ReportedClock;

// What the clock check accepts of a camera: its stamp (start of exposure, or the frame's end)
// lies before the frame's arrival by the exposure, readout and transfer, tens of milliseconds
// that vary with the exposure. That is a camera working, not a clock error; a LiDAR's defaults
// (10 ms offset, 5 ms spread) would warn on every camera. 250 ms offset, 50 ms spread.
timing::ClockTolerance camera_clock_tolerance() noexcept;

// What a GenICam camera says of its PTP clock: the SFNC features (PtpEnable, PtpStatus,
// PtpServoStatus, PtpOffsetFromMaster, PtpGrandmasterClockID) or their older GigE Vision names
// (GevIEEE1588, GevIEEE1588Status…), as far as the camera has them.
struct PtpReading {
  bool has_ptp = false;            // the camera has a PTP enable feature at all
  bool enabled = false;            // PtpEnable / GevIEEE1588
  std::string status;              // PtpStatus / GevIEEE1588Status(Latched): "Slave", "Master"…; "" none
  std::string servo;               // PtpServoStatus: "Locked", "Unknown"; "" none
  std::optional<std::int64_t> offset_from_master_ns;
  std::optional<std::uint64_t> grandmaster;  // the grandmaster's 8-byte clock identity
};

// The clock a camera reports, for stamps in the camera's clock (`device_time`) or the host's
// receive time. PTP on: source ptp, state from the port state (Slave → locked, or acquiring
// while the servo is not locked; Listening, PreMaster, Uncalibrated, Initializing, Passive →
// acquiring; Faulty → holdover; Master → free_running, the camera being the network's clock;
// Disabled → free_running), offset and grandmaster as read. Without PTP (or with it off): the
// host's clock for host stamps (state unknown: the host's own synchronisation is judged apart),
// free_running for the camera's own clock, which counts from power-up.
ClockStatus genicam_clock_status(const PtpReading& ptp, bool device_time, std::int64_t reported_ns);

// A PTP clock identity as ptp4l prints it: "001122.fffe.334455".
std::string clock_identity_text(std::uint64_t identity);

}  // namespace sim::camera
