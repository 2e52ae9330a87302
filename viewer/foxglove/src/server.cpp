// SPDX-License-Identifier: Apache-2.0
// The listener and the HTTP side: every connection starts as HTTP; a WebSocket upgrade asking
// for foxglove.websocket.v1 becomes a WsSession, any other GET is answered from the page API.
#include "sim/foxglove/server.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <cstdio>
#include <random>
#include <set>
#include <thread>

#include "catalog.hpp"
#include "hub.hpp"
#include "page_api.hpp"
#include "page_frames.hpp"
#include "ws_session.hpp"

namespace sim::foxglove {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using namespace std::chrono_literals;

namespace {

// Whether the client's Sec-WebSocket-Protocol list names ours.
bool offers_subprotocol(std::string_view list) {
  while (!list.empty()) {
    const auto comma = list.find(',');
    std::string_view item = list.substr(0, comma);
    list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 1);
    while (!item.empty() && (item.front() == ' ' || item.front() == '\t')) item.remove_prefix(1);
    while (!item.empty() && (item.back() == ' ' || item.back() == '\t')) item.remove_suffix(1);
    if (item == kSubprotocol) return true;
  }
  return false;
}

std::string_view view(beast::string_view text) { return {text.data(), text.size()}; }

std::string random_session_id() {
  std::random_device device;
  char text[17];
  std::snprintf(text, sizeof text, "%08x%08x", device(), device());
  return text;
}

}  // namespace

struct Server::Impl {
  explicit Impl(const ServerOptions& o)
      : options(o),
        hub(PumpOptions{encode_options(o), o.max_rate_hz, o.trust}),
        frames(o.jpeg_quality, o.trust),
        catalog(o.streams, encode_options(o), o.poll_interval,
                [this](const auto& added, const auto& removed) { hub.update(added, removed); },
                [this] { after_poll(); }),
        acceptor(ioc) {
    session.server_name = o.name;
    session.session_id = random_session_id();
    session.max_rate_hz = o.max_rate_hz;
    session.send_timeout = o.send_timeout;
  }

  static EncodeOptions encode_options(const ServerOptions& o) {
    return {o.compress_jpeg ? ImageCompression::jpeg : ImageCompression::none, o.jpeg_quality};
  }

  void after_poll() {
    hub.reap();
    std::set<std::string> names;
    for (const auto& e : catalog.snapshot()) names.insert(e.name);
    frames.keep_only(names);
  }

  void accept();
  void stop();

  ServerOptions options;
  SessionOptions session;
  Hub hub;
  PageFrames frames;
  Catalog catalog;
  // Declared after the hub: destroyed first, so sessions never outlive the hub they refer to.
  net::io_context ioc;
  tcp::acceptor acceptor;
  std::vector<std::thread> threads;
  bool stopped = false;
};

namespace {

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, Server::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(16 * 1024);
    parser_->body_limit(16 * 1024);
    stream_.expires_after(30s);  // a client that sends nothing is dropped
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) {
                       self->on_read(ec);
                     });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec) {
      // A malformed request gets a 400 before the connection closes; a vanished client nothing.
      if (ec != http::error::end_of_stream && ec != beast::error::timeout &&
          ec != net::error::operation_aborted && ec != net::error::connection_reset &&
          ec != net::error::eof) {
        return reply_error(http::status::bad_request,
                           "The request is not valid HTTP/1.1; send a plain GET.", 11, false);
      }
      return shut();
    }
    auto request = parser_->release();
    if (websocket::is_upgrade(request)) {
      if (!offers_subprotocol(view(request[http::field::sec_websocket_protocol]))) {
        return reply_error(http::status::bad_request,
                           "This server speaks the Foxglove WebSocket protocol: connect with the "
                           "subprotocol foxglove.websocket.v1 (Foxglove or Lichtblick does).",
                           request.version(), false);
      }
      std::make_shared<WsSession>(std::move(stream_), server_.hub, server_.session)
          ->start(std::move(request));
      return;
    }
    respond(request);
  }

  void respond(const http::request<http::string_body>& request) {
    const unsigned version = request.version();
    const bool keep_alive = request.keep_alive();
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      return reply_error(http::status::method_not_allowed, "Only GET is served here.", version,
                         keep_alive);
    }
    const auto target = parse_target(view(request.target()));
    if (!target) {
      return reply_error(http::status::bad_request,
                         "The address is malformed; open / for the page.", version, keep_alive);
    }
    if (target->path == "/" || target->path == "/index.html") {
      return reply("text/html; charset=utf-8", std::string(kPageHtml), version, keep_alive,
                   request.method() == http::verb::head);
    }
    if (target->path == "/api/streams") {
      return reply("application/json", streams_json(server_.catalog.snapshot()), version,
                   keep_alive, request.method() == http::verb::head);
    }
    if (target->path == "/api/image" || target->path == "/api/topdown") {
      const auto it = target->query.find("stream");
      if (it == target->query.end() || !server_.catalog.find(it->second)) {
        return reply_error(http::status::not_found,
                           "No such stream here; /api/streams lists the streams.", version,
                           keep_alive);
      }
      Expected<Picture> picture = Error{ErrorCode::invalid_argument, ""};
      if (target->path == "/api/image") {
        picture = server_.frames.image(it->second);
      } else {
        TopDownOptions options;
        if (const auto c = target->query.find("color"); c != target->query.end()) {
          options.color = c->second == "intensity" ? ColorBy::intensity : ColorBy::height;
        }
        if (const auto r = target->query.find("range"); r != target->query.end()) {
          char* end = nullptr;
          const float range = std::strtof(r->second.c_str(), &end);
          if (end != r->second.c_str() && range >= 1.0f && range <= 1000.0f) {
            options.range_m = range;
          }
        }
        picture = server_.frames.top_down(it->second, options);
      }
      if (!picture) {
        return reply_error(http::status::service_unavailable, picture.error().message, version,
                           keep_alive);
      }
      return reply_bytes("image/jpeg", *picture, version, keep_alive,
                         request.method() == http::verb::head);
    }
    reply_error(http::status::not_found, "Nothing here; open / for the page.", version,
                keep_alive);
  }

  void reply(const char* type, std::string body, unsigned version, bool keep_alive,
             bool head = false) {
    auto response = std::make_shared<http::response<http::string_body>>(http::status::ok, version);
    response->set(http::field::server, "sim_foxglove");
    response->set(http::field::content_type, type);
    response->set(http::field::cache_control, "no-store");
    response->keep_alive(keep_alive);
    response->body() = std::move(body);
    response->prepare_payload();
    if (head) response->body().clear();
    send(response, keep_alive);
  }

  void reply_bytes(const char* type, const Picture& picture, unsigned version, bool keep_alive,
                   bool head) {
    const Jpeg& bytes = picture.jpeg;
    auto response =
        std::make_shared<http::response<http::buffer_body>>(http::status::ok, version);
    response->set(http::field::server, "sim_foxglove");
    response->set(http::field::content_type, type);
    response->set(http::field::cache_control, "no-store");
    response->keep_alive(keep_alive);
    response->set("X-Sim-View", picture.caption);
    response->content_length(bytes->size());
    response->body().data = head ? nullptr : const_cast<std::byte*>(bytes->data());
    response->body().size = head ? 0 : bytes->size();
    response->body().more = false;
    held_ = bytes;  // the body points into it until the write completes
    send(response, keep_alive);
  }

  void reply_error(http::status status, std::string sentence, unsigned version, bool keep_alive) {
    auto response = std::make_shared<http::response<http::string_body>>(status, version);
    response->set(http::field::server, "sim_foxglove");
    response->set(http::field::content_type, "text/plain; charset=utf-8");
    response->keep_alive(keep_alive);
    response->body() = std::move(sentence) + "\n";
    response->prepare_payload();
    send(response, keep_alive);
  }

  template <typename Response>
  void send(const std::shared_ptr<Response>& response, bool keep_alive) {
    stream_.expires_after(30s);
    http::async_write(stream_, *response,
                      [self = shared_from_this(), response, keep_alive](beast::error_code ec,
                                                                        std::size_t) {
                        self->held_.reset();
                        if (ec || !keep_alive) return self->shut();
                        self->read();
                      });
  }

  void shut() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.close();
  }

  beast::tcp_stream stream_;
  Server::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  Jpeg held_;
};

}  // namespace

void Server::Impl::accept() {
  acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
    if (!ec) std::make_shared<HttpSession>(std::move(socket), *this)->read();
    accept();
  });
}

void Server::Impl::stop() {
  if (stopped) return;
  stopped = true;
  catalog.stop();
  net::post(ioc, [this] {
    beast::error_code ignored;
    acceptor.close(ignored);
  });
  ioc.stop();
  for (auto& t : threads) t.join();
  threads.clear();
  hub.stop();  // pumps end before the sessions they hold are destroyed with the io_context
}

Expected<Server> Server::start(const ServerOptions& options) {
  beast::error_code ec;
  const auto address = net::ip::make_address(options.bind, ec);
  if (ec) {
    return Error{ErrorCode::invalid_argument,
                 "--bind " + options.bind + " is not an IP address; use e.g. 127.0.0.1 or 0.0.0.0."};
  }
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
    return Error{ErrorCode::invalid_argument, "the JPEG quality must be from 1 to 100."};
  }
  auto impl = std::make_unique<Impl>(options);
  const tcp::endpoint endpoint(address, options.port);
  impl->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl->acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl->acceptor.bind(endpoint, ec);
  if (!ec) impl->acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    return Error{ErrorCode::system_error,
                 "cannot listen on " + options.bind + ":" + std::to_string(options.port) + " (" +
                     ec.message() + "); choose another --port (0 picks a free one)."};
  }
  impl->catalog.start();
  impl->accept();
  const unsigned threads = std::max(1u, options.io_threads);
  for (unsigned i = 0; i < threads; ++i) {
    impl->threads.emplace_back([io = &impl->ioc] { io->run(); });
  }
  return Server(std::move(impl));
}

Server::Server(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Server::Server(Server&&) noexcept = default;
Server& Server::operator=(Server&& other) noexcept {
  if (this != &other) {
    stop();
    impl_ = std::move(other.impl_);
  }
  return *this;
}
Server::~Server() { stop(); }

std::uint16_t Server::port() const noexcept {
  beast::error_code ec;
  return impl_ ? impl_->acceptor.local_endpoint(ec).port() : 0;
}

void Server::stop() {
  if (impl_) impl_->stop();
}

}  // namespace sim::foxglove
