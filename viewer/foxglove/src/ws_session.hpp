// SPDX-License-Identifier: Apache-2.0
// One Foxglove client over WebSocket (the session itself is private to ws_session.cpp).
// Freshness first: each subscription holds at most one pending message (a newer one replaces
// it), text messages (advertise, status) keep their order in a short bounded queue, and one write
// is in flight at a time. A client that stops reading is closed after the send timeout; one that
// floods requests while not reading is closed when its status queue fills. Memory per client is
// bounded either way.
//
// Why only a function here: Beast's WebSocket stream and its composed operations are the heaviest
// compile of the project (docs/build-times.md); this header keeps <boost/beast/websocket.hpp>
// out of every file but ws_session.cpp, so the stream is instantiated once.
#pragma once

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <string_view>

namespace sim::foxglove {

class Hub;

struct SessionOptions {
  std::string server_name;
  std::string session_id;
  double max_rate_hz = 0;
  std::chrono::milliseconds send_timeout{10'000};
};

// Completes the WebSocket handshake for `request` (already checked for the subprotocol) on
// `socket`, then serves the client until it or the server goes. `subprotocol`: the name to
// answer with (the one the client offered); `connection` is held while the session lives (the
// server's connection count).
void start_ws_session(boost::asio::ip::tcp::socket socket,
                      boost::beast::http::request<boost::beast::http::string_body> request,
                      Hub& hub, const SessionOptions& options, std::string_view subprotocol,
                      std::shared_ptr<void> connection);

}  // namespace sim::foxglove
