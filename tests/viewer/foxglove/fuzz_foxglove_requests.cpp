// SPDX-License-Identifier: Apache-2.0
// libFuzzer over what sim_foxglove parses from the network, chosen by the first byte modulo 4:
// a client's JSON request (0), the page API's request target (1), Sec-WebSocket-Protocol lines
// split at newlines (2), and a Host and an Origin header split at the first newline (3). None
// may crash, read out of bounds or throw; every input becomes a request or a plain refusal.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include <vector>

#include "access.hpp"
#include "page_api.hpp"
#include "sim/foxglove/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 4 == 2) {
    std::vector<std::string_view> lines;
    std::string_view rest = text;
    while (!rest.empty()) {
      const auto newline = rest.find('\n');
      lines.push_back(rest.substr(0, newline));
      rest = newline == std::string_view::npos ? std::string_view{} : rest.substr(newline + 1);
    }
    (void)sim::foxglove::choose_subprotocol(lines);
  } else if (data[0] % 4 == 3) {
    static const sim::foxglove::AccessPolicy policy({"https://viewer.example:8443/"}, "vehicle");
    const auto newline = text.find('\n');
    const std::string_view host = text.substr(0, newline);
    const std::string_view origin =
        newline == std::string_view::npos ? std::string_view{} : text.substr(newline + 1);
    (void)policy.host_problem(host);
    (void)policy.origin_problem(origin, host);
  } else if (data[0] % 4 == 0) {
    const auto request = sim::foxglove::parse_client_request(text);
    if (const auto* rejected = std::get_if<sim::foxglove::RejectedRequest>(&request)) {
      // The refusal goes back to the client as a status message: it must serialize.
      (void)sim::foxglove::status_json(sim::foxglove::StatusLevel::error, rejected->message);
    }
  } else {
    (void)sim::foxglove::parse_target(text);
  }
  return 0;
}
