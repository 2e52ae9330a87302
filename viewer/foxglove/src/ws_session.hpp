// SPDX-License-Identifier: Apache-2.0
// One Foxglove client over WebSocket. Freshness first: each subscription holds at most one
// pending message (a newer one replaces it), text messages (advertise, status) keep their order
// in a short bounded queue, and one write is in flight at a time. A client that stops reading is
// closed after the send timeout; one that floods requests while not reading is closed when its
// status queue fills. Memory per client is bounded either way.
#pragma once

#include <atomic>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "hub.hpp"
#include "sim/foxglove/protocol.hpp"

namespace sim::foxglove {

struct SessionOptions {
  std::string server_name;
  std::string session_id;
  double max_rate_hz = 0;
  std::chrono::milliseconds send_timeout{10'000};
};

class WsSession final : public Client, public std::enable_shared_from_this<WsSession> {
 public:
  // `subprotocol`: the name to answer with (the one the client offered); `connection` is held
  // while the session lives (the server's connection count).
  WsSession(boost::beast::tcp_stream&& stream, Hub& hub, const SessionOptions& options,
            std::string_view subprotocol, std::shared_ptr<void> connection);
  ~WsSession() override;

  // Completes the WebSocket handshake for `request` (already checked for the subprotocol).
  void start(boost::beast::http::request<boost::beast::http::string_body> request);

  void offer(std::shared_ptr<const Message> message) override;
  void send_text(std::string text) override;
  void drop_channel(std::uint32_t channel_id) override;

 private:
  struct Slot {
    std::uint32_t subscription_id = 0;
    std::shared_ptr<const Message> pending;
    std::chrono::steady_clock::time_point next_due{};
  };

  void on_accept(boost::beast::error_code ec);
  void read();
  void on_read(boost::beast::error_code ec, std::size_t bytes);
  void handle(std::string_view text);
  void subscribe(const SubscribeRequest& request);
  void unsubscribe(const UnsubscribeRequest& request);
  void kick();
  void write_next();
  void on_write(boost::beast::error_code ec);
  void watch();
  void close();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  Hub& hub_;
  const SessionOptions options_;
  const std::string subprotocol_;
  const std::shared_ptr<void> connection_;
  boost::beast::flat_buffer read_buffer_;
  boost::asio::steady_timer rate_timer_;
  boost::asio::steady_timer watchdog_;

  // Shared with the pump threads and the hub.
  std::mutex mutex_;
  std::map<std::uint32_t, Slot> slots_;  // by channel id
  std::deque<std::string> texts_;
  bool text_overflow_ = false;
  std::atomic<bool> kick_pending_{false};

  // Only on the session's strand.
  std::map<std::uint32_t, std::uint32_t> subscriptions_;  // subscription id -> channel id
  bool open_ = false;
  bool closed_ = false;
  bool writing_ = false;
  bool rate_timer_armed_ = false;
  std::chrono::steady_clock::time_point write_started_{};
  std::uint32_t next_channel_turn_ = 0;  // round robin among channels
  std::string current_text_;
  std::shared_ptr<const Message> current_message_;
  std::array<std::byte, kMessageHeaderSize> current_header_{};
};

}  // namespace sim::foxglove
