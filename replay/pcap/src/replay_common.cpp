// SPDX-License-Identifier: Apache-2.0
#include "replay_common.hpp"

#include <cstdio>
#include <string>

namespace sim::pcap {

int finish_replay(const apps::CommandLine& cli, const ReplayArgs& r, const ReplayResult& result,
                  const ReplayTarget& target, const std::string& decoded_as,
                  const apps::StopSignal& stop) {
  if (result.empty_window) {
    char message[512];
    std::snprintf(message, sizeof message,
                  "the window from --start %.3f s of %s holds no packet (the capture lasts "
                  "%.3f s); choose an earlier --start",
                  r.start_s, r.file.c_str(), result.capture_span_s);
    return cli.fail(message);
  }
  if (r.summary) {
    std::printf("summary %s datagrams=%llu skipped=%llu passes=%u other_senders=%llu\n", target.summary().c_str(),
                static_cast<unsigned long long>(result.datagrams),
                static_cast<unsigned long long>(result.skipped), result.passes,
                static_cast<unsigned long long>(result.other_senders));
    std::fflush(stdout);
  }
  if (result.read_error) {
    return cli.fail(*result.read_error + " " + std::to_string(target.frames()) +
                    " frames were published before the damage.");
  }
  if (!stop.requested() && target.decoded_packets() == 0) {
    return cli.fail("no packet of " + r.file + " could be decoded " + decoded_as);
  }
  return apps::kExitOk;
}

}  // namespace sim::pcap
