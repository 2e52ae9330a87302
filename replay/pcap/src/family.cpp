// SPDX-License-Identifier: Apache-2.0
#include "family.hpp"

#include <charconv>
#include <optional>
#include <system_error>

namespace sim::pcap {
namespace {

bool ends_with(std::string_view text, std::string_view end) {
  return text.size() >= end.size() && text.substr(text.size() - end.size()) == end;
}

// The value of `--name VALUE` or `--name=VALUE` at argv[i] (i moves past a separate value).
std::optional<std::string_view> value_of(std::string_view name, int argc, char** argv, int& i) {
  const std::string_view arg = argv[i];
  if (arg == name) {
    if (i + 1 >= argc) return std::nullopt;
    return std::string_view(argv[++i]);
  }
  if (arg.size() > name.size() && arg.substr(0, name.size()) == name && arg[name.size()] == '=') {
    return arg.substr(name.size() + 1);
  }
  return std::nullopt;
}

std::optional<std::uint16_t> port_number(std::string_view text) {
  unsigned number = 0;
  const auto [end, failure] = std::from_chars(text.data(), text.data() + text.size(), number);
  if (failure != std::errc{} || end != text.data() + text.size() || number > 65535) return std::nullopt;
  return static_cast<std::uint16_t>(number);
}

}  // namespace

// Only the few options that choose the family and the head are read here; every family parses
// the whole command line again with its own options, and refuses what is wrong there.
Request read_request(int argc, char** argv) {
  Request request;
  request.argc = argc;
  request.argv = argv;
  for (int i = 1; i < argc; ++i) {
    if (const auto model = value_of("--model", argc, argv, i)) {
      request.model = *model;
    } else if (const auto calibration = value_of("--calibration", argc, argv, i)) {
      request.calibration = *calibration;
    } else if (const auto metadata = value_of("--metadata", argc, argv, i)) {
      request.calibration = *metadata;
    } else if (const auto port = value_of("--port", argc, argv, i)) {
      request.capture.port = port_number(*port);
    } else if (const auto filter = value_of("--filter", argc, argv, i)) {
      request.capture.filter = *filter;
    } else {
      const std::string_view arg = argv[i];
      if (!arg.empty() && arg.front() != '-' && (ends_with(arg, ".pcap") || ends_with(arg, ".pcapng"))) {
        request.file = arg;
      }
    }
  }
  return request;
}

Claim packets_claim(std::uint32_t packets) noexcept {
  return packets == 0 ? Claim{} : Claim{Evidence::packets, packets};
}

}  // namespace sim::pcap
