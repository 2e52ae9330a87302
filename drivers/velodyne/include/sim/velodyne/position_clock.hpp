// SPDX-License-Identifier: Apache-2.0
// A Velodyne's clock as data: what a position packet (port 8308) says of the sensor's
// synchronisation, as the stream's clock record (sim::ClockStatus). The sensor stamps with a
// counter of microseconds since the top of the hour; with PPS locked it is aligned to the GNSS
// pulse and set from the NMEA time, without PPS it free-runs (stamps drift, up to 30 min off).
//
//   auto report = sim::velodyne::parse_position_packet(payload, model);
//   if (report) latest = sim::velodyne::clock_status_of(*report, arrival_ns);
//
// Only the reported fields are set (and a verdict of warn with its sentence when the report
// alone shows a problem); the measured fields and the final verdict are the clock check's
// (sim::timing::ClockCheck), which compares each data packet's time with its arrival.
#pragma once

#include <cstdint>

#include "sim/clock_status.hpp"
#include "sim/velodyne/packet.hpp"

namespace sim::velodyne {

// The clock a position packet reports: source pps_nmea; state from the PPS byte (locked →
// locked, synchronizing → acquiring, absent → free_running, error → holdover; an HDL-32E/64E,
// which reports no PPS state, from its NMEA fix); stamps sensor; reported_ns as given (the
// packet's arrival, CLOCK_REALTIME). Verdict warn with one sentence when the PPS is not locked,
// the PPS byte or the NMEA sentence is unreadable, the receiver has no fix, or the top-of-hour
// counter disagrees with the NMEA time; unknown (to be measured) otherwise.
ClockStatus clock_status_of(const PositionReport& report, std::int64_t reported_ns);

// How far apart the top-of-hour counter and the NMEA time may be with PPS locked: the sentence
// is up to a second older than the packet, and the counter runs on.
inline constexpr std::int64_t max_nmea_disagreement_s = 3;

}  // namespace sim::velodyne
