// SPDX-License-Identifier: Apache-2.0
// The one translation unit that instantiates Beast's WebSocket stream. What its compile costs is
// the code of Beast's composed operations, instantiated once per distinct stream, buffer and
// handler type (docs/build-times.md), so: the next layer is a plain socket (the WebSocket layer
// keeps its own timeouts; a beast::tcp_stream adds its timed operations to every read and write),
// permessage-deflate is compiled out (deflateSupported = false; it was never enabled, so the
// handshake and the frames are the same), and every write goes through one call (one buffer
// type, one handler type).
#include "ws_session.hpp"

#include <array>
#include <atomic>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/websocket/stream.hpp>
#include <deque>
#include <map>
#include <mutex>

#include "hub.hpp"
#include "sim/foxglove/protocol.hpp"

namespace sim::foxglove {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace http = beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using namespace std::chrono_literals;

namespace {

class WsSession final : public Client, public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket&& socket, Hub& hub, const SessionOptions& options,
            std::string_view subprotocol, std::shared_ptr<void> connection);
  ~WsSession() override;

  // Completes the WebSocket handshake for `request`.
  void start(http::request<http::string_body> request);

  void offer(std::shared_ptr<const Message> message) override;
  void send_text(std::string text) override;
  void drop_channel(std::uint32_t channel_id) override;

 private:
  struct Slot {
    std::uint32_t subscription_id = 0;
    std::shared_ptr<const Message> pending;
    std::chrono::steady_clock::time_point next_due{};
  };

  void on_accept(beast::error_code ec);
  void read();
  void on_read(beast::error_code ec, std::size_t bytes);
  void handle(std::string_view text);
  void subscribe(const SubscribeRequest& request);
  void unsubscribe(const UnsubscribeRequest& request);
  void kick();
  void write_next();
  void write(bool text, const std::array<net::const_buffer, 2>& buffers,
             std::chrono::steady_clock::time_point now);
  void on_write(beast::error_code ec);
  void watch();
  void close();

  websocket::stream<tcp::socket, /*deflateSupported=*/false> ws_;
  Hub& hub_;
  const SessionOptions options_;
  const std::string subprotocol_;
  const std::shared_ptr<void> connection_;
  beast::flat_buffer read_buffer_;
  net::steady_timer rate_timer_;
  net::steady_timer watchdog_;

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

// Client messages are small JSON requests; anything bigger is refused by the WebSocket layer.
constexpr std::size_t kMaxClientMessage = 64 * 1024;
// Status and advertise messages waiting for a client that does not read; more closes it.
constexpr std::size_t kMaxQueuedTexts = 256;
// Ids named in one status; a request with more bad ids gets "… and N more".
constexpr std::size_t kIdsPerStatus = 16;

// "1, 2, 3" or "1, 2, …, 16 and 284 more".
std::string id_list(const std::vector<std::uint32_t>& ids) {
  std::string out;
  for (std::size_t i = 0; i < ids.size() && i < kIdsPerStatus; ++i) {
    if (i > 0) out += ", ";
    out += std::to_string(ids[i]);
  }
  if (ids.size() > kIdsPerStatus) out += " and " + std::to_string(ids.size() - kIdsPerStatus) + " more";
  return out;
}

// "<what>: <ids>; <what to do>." added to `status`, or nothing when there are no ids.
void add_problem(std::string& status, const std::vector<std::uint32_t>& ids, const char* what,
                 const char* what_to_do) {
  if (ids.empty()) return;
  if (!status.empty()) status += ' ';
  status += std::string(what) + ": " + id_list(ids) + "; " + what_to_do + ".";
}

WsSession::WsSession(tcp::socket&& socket, Hub& hub, const SessionOptions& options,
                     std::string_view subprotocol, std::shared_ptr<void> connection)
    : ws_(std::move(socket)),
      hub_(hub),
      options_(options),
      subprotocol_(subprotocol),
      connection_(std::move(connection)),
      rate_timer_(ws_.get_executor()),
      watchdog_(ws_.get_executor()) {}

WsSession::~WsSession() = default;

void WsSession::start(http::request<http::string_body> request) {
  websocket::stream_base::timeout timeouts =
      websocket::stream_base::timeout::suggested(beast::role_type::server);
  timeouts.handshake_timeout = 10s;
  timeouts.idle_timeout = std::chrono::duration_cast<std::chrono::seconds>(
      std::max<std::chrono::milliseconds>(options_.send_timeout * 3, 3s));
  timeouts.keep_alive_pings = true;
  ws_.set_option(timeouts);
  ws_.set_option(websocket::stream_base::decorator([name = subprotocol_](
                                                     websocket::response_type& response) {
    response.set(http::field::sec_websocket_protocol, name);
    response.set(http::field::server, "sim_foxglove");
  }));
  ws_.read_message_max(kMaxClientMessage);
  ws_.auto_fragment(false);
  ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
    self->on_accept(ec);
  });
}

void WsSession::on_accept(beast::error_code ec) {
  if (ec) return close();
  open_ = true;
  send_text(server_info_json(options_.server_name, options_.session_id));
  hub_.join(shared_from_this());
  read();
  watch();
}

void WsSession::read() {
  ws_.async_read(read_buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t n) {
    self->on_read(ec, n);
  });
}

void WsSession::on_read(beast::error_code ec, std::size_t) {
  // Malformed frames, oversized messages and closes all end here: the WebSocket layer has
  // already answered with the right close code.
  if (ec) return close();
  if (!ws_.got_text()) {
    send_text(status_json(StatusLevel::error,
                          "binary client messages (client publish) are not offered by this server."));
  } else {
    const auto data = read_buffer_.cdata();
    handle(std::string_view(static_cast<const char*>(data.data()), data.size()));
  }
  read_buffer_.consume(read_buffer_.size());
  if (!closed_) read();
}

void WsSession::handle(std::string_view text) {
  const ClientRequest request = parse_client_request(text);
  if (const auto* rejected = std::get_if<RejectedRequest>(&request)) {
    send_text(status_json(StatusLevel::error, rejected->message));
    return;
  }
  if (const auto* request_to_subscribe = std::get_if<SubscribeRequest>(&request)) {
    return subscribe(*request_to_subscribe);
  }
  unsubscribe(std::get<UnsubscribeRequest>(request));
}

// Every bad id of one request is named in one status: a request of many ids must not earn as
// many statuses (a client that reads everything would still overflow the text queue).
void WsSession::subscribe(const SubscribeRequest& request) {
  std::vector<std::uint32_t> ids_in_use, channels_taken, channels_unknown;
  for (const Subscription& s : request.subscriptions) {
    if (subscriptions_.contains(s.id)) {
      ids_in_use.push_back(s.id);
      continue;
    }
    bool taken = false;
    for (const auto& [id, channel] : subscriptions_) taken |= channel == s.channel_id;
    if (taken) {
      channels_taken.push_back(s.channel_id);
      continue;
    }
    {
      std::lock_guard lock(mutex_);
      slots_[s.channel_id] = Slot{s.id, nullptr, {}};
    }
    if (!hub_.subscribe(shared_from_this(), s.channel_id)) {
      std::lock_guard lock(mutex_);
      slots_.erase(s.channel_id);
      channels_unknown.push_back(s.channel_id);
      continue;
    }
    subscriptions_[s.id] = s.channel_id;
  }
  std::string status;
  add_problem(status, ids_in_use, "Subscription ids already in use", "choose other ids");
  add_problem(status, channels_taken, "Channels this client already subscribes to",
              "one subscription per channel");
  add_problem(status, channels_unknown, "Channels not advertised",
              "subscribe to channel ids from an advertise message");
  if (!status.empty()) send_text(status_json(StatusLevel::error, status));
}

void WsSession::unsubscribe(const UnsubscribeRequest& request) {
  std::vector<std::uint32_t> inactive;
  for (const std::uint32_t id : request.subscription_ids) {
    const auto it = subscriptions_.find(id);
    if (it == subscriptions_.end()) {
      inactive.push_back(id);
      continue;
    }
    const std::uint32_t channel_id = it->second;
    subscriptions_.erase(it);
    {
      std::lock_guard lock(mutex_);
      slots_.erase(channel_id);
    }
    hub_.unsubscribe(this, channel_id);
  }
  std::string status;
  add_problem(status, inactive, "Subscription ids not active", "nothing to unsubscribe");
  if (!status.empty()) send_text(status_json(StatusLevel::warning, status));
}

void WsSession::offer(std::shared_ptr<const Message> message) {
  {
    std::lock_guard lock(mutex_);
    const auto it = slots_.find(message->channel_id);
    if (it == slots_.end()) return;
    it->second.pending = std::move(message);  // the older pending message, if any, is dropped
  }
  kick();
}

void WsSession::send_text(std::string text) {
  {
    std::lock_guard lock(mutex_);
    if (texts_.size() >= kMaxQueuedTexts) {
      text_overflow_ = true;
    } else {
      texts_.push_back(std::move(text));
    }
  }
  kick();
}

void WsSession::drop_channel(std::uint32_t channel_id) {
  std::lock_guard lock(mutex_);
  slots_.erase(channel_id);
  // subscriptions_ belongs to the strand; the stale entry is removed there on the next kick.
}

void WsSession::kick() {
  if (kick_pending_.exchange(true)) return;
  net::post(ws_.get_executor(), [self = shared_from_this()] {
    self->kick_pending_.store(false);
    self->write_next();
  });
}

void WsSession::write_next() {
  if (!open_ || closed_ || writing_) return;
  const auto now = std::chrono::steady_clock::now();
  std::unique_lock lock(mutex_);
  // Channels the hub dropped: forget their subscriptions so the ids can be used again.
  std::erase_if(subscriptions_, [&](const auto& s) { return !slots_.contains(s.second); });
  if (text_overflow_) {
    lock.unlock();
    return close();
  }
  if (!texts_.empty()) {
    current_text_ = std::move(texts_.front());
    texts_.pop_front();
    lock.unlock();
    return write(true, {net::buffer(current_text_), net::const_buffer()}, now);
  }
  // The next due message, taking channels in turn so a fast stream cannot starve a slow one.
  Slot* chosen = nullptr;
  std::uint32_t chosen_channel = 0;
  std::optional<std::chrono::steady_clock::time_point> earliest;
  auto consider = [&](std::uint32_t channel, Slot& slot) {
    if (!slot.pending || chosen != nullptr) return;
    if (slot.next_due > now) {
      if (!earliest || slot.next_due < *earliest) earliest = slot.next_due;
      return;
    }
    chosen = &slot;
    chosen_channel = channel;
  };
  for (auto it = slots_.upper_bound(next_channel_turn_); it != slots_.end(); ++it) {
    consider(it->first, it->second);
  }
  for (auto it = slots_.begin(); it != slots_.end() && it->first <= next_channel_turn_; ++it) {
    consider(it->first, it->second);
  }
  if (chosen == nullptr) {
    lock.unlock();
    if (earliest && !rate_timer_armed_) {
      rate_timer_armed_ = true;
      rate_timer_.expires_at(*earliest);
      rate_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
        self->rate_timer_armed_ = false;
        if (!ec) self->write_next();
      });
    }
    return;
  }
  current_message_ = std::move(chosen->pending);
  current_header_ = message_header(chosen->subscription_id, current_message_->timestamp_ns);
  if (options_.max_rate_hz > 0) {
    chosen->next_due = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(1.0 / options_.max_rate_hz));
  }
  next_channel_turn_ = chosen_channel;
  lock.unlock();
  write(false,
        {net::buffer(current_header_),
         net::buffer(current_message_->payload.data(), current_message_->payload.size())},
        now);
}

// A text message (its second buffer empty) or a binary one (header, payload): one message, one
// frame. The only async_write of the session, so Beast's write operation is instantiated once.
void WsSession::write(bool text, const std::array<net::const_buffer, 2>& buffers,
                      std::chrono::steady_clock::time_point now) {
  writing_ = true;
  write_started_ = now;
  ws_.text(text);
  ws_.async_write(buffers, [self = shared_from_this()](beast::error_code ec, std::size_t) {
    self->on_write(ec);
  });
}

void WsSession::on_write(beast::error_code ec) {
  writing_ = false;
  current_message_.reset();
  current_text_.clear();
  if (ec) return close();
  write_next();
}

// Once a second: a write that has not finished within the send timeout means the client
// stopped reading; closing it frees what it held.
void WsSession::watch() {
  watchdog_.expires_after(1s);
  watchdog_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (ec || self->closed_) return;
    if (self->writing_ &&
        std::chrono::steady_clock::now() - self->write_started_ > self->options_.send_timeout) {
      return self->close();
    }
    self->watch();
  });
}

void WsSession::close() {
  if (closed_) return;
  closed_ = true;
  hub_.leave(this);
  {
    std::lock_guard lock(mutex_);
    slots_.clear();
    texts_.clear();
  }
  rate_timer_.cancel();
  watchdog_.cancel();
  // Closing the socket ends every pending operation; no close handshake with a client that
  // may not be reading.
  beast::error_code ignored;
  ws_.next_layer().shutdown(tcp::socket::shutdown_both, ignored);
  ws_.next_layer().close(ignored);
}

}  // namespace

void start_ws_session(tcp::socket socket, http::request<http::string_body> request, Hub& hub,
                      const SessionOptions& options, std::string_view subprotocol,
                      std::shared_ptr<void> connection) {
  std::make_shared<WsSession>(std::move(socket), hub, options, subprotocol, std::move(connection))
      ->start(std::move(request));
}

}  // namespace sim::foxglove
