// SPDX-License-Identifier: Apache-2.0
// libFuzzer over what sim_foxglove parses from the network: a client's JSON request (first byte
// even) and the page API's request target (first byte odd). Neither may crash, read out of
// bounds or throw; every input becomes a request or a plain refusal.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "page_api.hpp"
#include "sim/foxglove/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 2 == 0) {
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
