// SPDX-License-Identifier: Apache-2.0
#include "replay_common.hpp"

#include <charconv>
#include <cstdio>
#include <string>
#include <string_view>
#include <system_error>

namespace sim::pcap {

CaptureOptions detection_options(int argc, char** argv) {
  CaptureOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    std::string_view value;
    bool port = false;
    if ((arg == "--port" || arg == "--filter") && i + 1 < argc) {
      port = arg == "--port";
      value = argv[i + 1];
    } else if (arg.rfind("--port=", 0) == 0) {
      port = true;
      value = arg.substr(7);
    } else if (arg.rfind("--filter=", 0) == 0) {
      value = arg.substr(9);
    } else {
      continue;
    }
    if (!port) {
      options.filter = std::string(value);
      continue;
    }
    unsigned number = 0;
    const auto [end, failure] = std::from_chars(value.data(), value.data() + value.size(), number);
    if (failure == std::errc{} && end == value.data() + value.size() && number <= 65535) {
      options.port = static_cast<std::uint16_t>(number);
    }
  }
  return options;
}

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
