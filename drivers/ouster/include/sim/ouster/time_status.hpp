// SPDX-License-Identifier: Apache-2.0
// What an Ouster sensor says about its clock over HTTP (GET /api/v1/time; FW ≤ 2.0:
// /api/v1/system/time), as a sim::ClockStatus. No I/O here; the client is
// sim/ouster/time_client.hpp. (Sources in docs/ouster.md, "Clock".)
//
//   {"sensor": {"timestamp": {"mode": "TIME_FROM_PTP_1588", …}, "sync_pulse_in": {"locked": 1, …},
//               "nmea": {"locked": 0, …}, …},
//    "ptp":    {"port_data_set": {"port_state": "SLAVE", "port_identity": "bc0fa7.fffe.123456-1", …},
//               "parent_data_set": {"grandmaster_identity": "001747.fffe.700038", …},
//               "current_data_set": {"offset_from_master": -2.0, "mean_path_delay": 26420.0, …},
//               "time_properties_data_set": {"current_utc_offset": 37,
//                                            "current_utc_offset_valid": 1, "ptp_timescale": 1, …},
//               "default_data_set": {"domain_number": 0, …}, …},
//    "system": {…}}
//
// timestamp mode → source: TIME_FROM_PTP_1588 ptp; TIME_FROM_SYNC_PULSE_IN sync_pulse, or
// pps_nmea when the NMEA input is locked; TIME_FROM_INTERNAL_OSC free_running. PTP state:
// port_state SLAVE → locked, unless the grandmaster is the sensor's own clock (then not
// synchronised); LISTENING/UNCALIBRATED/INITIALIZING → acquiring; anything else free_running.
#pragma once

#include <string_view>

#include "sim/clock_status.hpp"
#include "sim/result.hpp"

namespace sim::ouster {

// The reported half of a ClockStatus from the /api/v1/time body (or an object holding only
// "sensor" and/or "ptp"); the caller sets reported_ns. A field missing or of another type is
// left unknown. Errors, one sentence: not JSON, not an object, neither "sensor" nor "ptp".
Expected<ClockStatus> clock_status_from_time_json(std::string_view json);

}  // namespace sim::ouster
