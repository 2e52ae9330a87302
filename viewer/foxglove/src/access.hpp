// SPDX-License-Identifier: Apache-2.0
// Who may talk to the server, decided from the request's headers alone (plain functions, fuzzed
// with the other parsers of client bytes):
//  - which Foxglove subprotocol a WebSocket client gets (it may offer several, on several lines);
//  - a browser page of another site may not open the WebSocket (WebSockets are not covered by
//    CORS, so the Origin header is checked) and may not read the page's API through DNS
//    rebinding (a name of the attacker's that resolves to this machine: the Host header is
//    checked). Native clients (Foxglove desktop, scripts) send no Origin and are not affected.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sim::foxglove {

// The subprotocol to answer with: the first one in the client's order that this server speaks
// (kSubprotocols), from every Sec-WebSocket-Protocol line; nullopt when none is offered.
std::optional<std::string_view> choose_subprotocol(const std::vector<std::string_view>& lines);

class AccessPolicy {
 public:
  // `allowed_origins`: ServerOptions::allowed_origins ("*" allows every origin and host).
  // `machine_name`: this machine's host name (gethostname), accepted as a Host.
  AccessPolicy(std::vector<std::string> allowed_origins, std::string machine_name);

  // Empty when a request with this Host header may be answered, else the sentence for the 403.
  // Accepted: no Host (not a browser), an IP address, localhost (and *.localhost), the machine's
  // name, and the host names of the allowed origins.
  std::string host_problem(std::string_view host) const;
  // Empty when a WebSocket upgrade with this Origin may proceed (its Host already accepted):
  // no Origin, this server's own page (http://HOST), Foxglove's web app, file:// (desktop
  // apps) or an allowed origin.
  std::string origin_problem(std::string_view origin, std::string_view host) const;

 private:
  bool any_ = false;
  std::vector<std::string> origins_;  // lower case, no trailing slash
  std::vector<std::string> hosts_;    // lower case host names without port
};

}  // namespace sim::foxglove
