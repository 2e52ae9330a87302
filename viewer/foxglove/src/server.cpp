// SPDX-License-Identifier: Apache-2.0
// The listener and the HTTP side: every connection starts as HTTP; a WebSocket upgrade asking
// for foxglove.websocket.v1 becomes a WebSocket session (ws_session.cpp), any other GET is
// answered from the page API. Only Beast's HTTP reading is compiled here:
// <boost/beast/websocket.hpp> stays in ws_session.cpp, and answers are written as bytes (send,
// below): Beast's composed operations are most of what these files cost to compile
// (docs/build-times.md).
#include "sim/foxglove/server.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core/buffers_to_string.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/string_body.hpp>
#include <boost/beast/websocket/rfc6455.hpp>
#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <random>
#include <set>
#include <thread>

#include "access.hpp"
#include "catalog.hpp"
#include "hub.hpp"
#include "page_api.hpp"
#include "page_frames.hpp"
#include "render_worker.hpp"
#include "ws_session.hpp"

namespace sim::foxglove {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using namespace std::chrono_literals;

namespace {

std::string_view view(beast::string_view text) { return {text.data(), text.size()}; }

// Every Sec-WebSocket-Protocol line of the request (RFC 6455 lets a client send several).
std::vector<std::string_view> subprotocol_lines(const http::request<http::string_body>& request) {
  std::vector<std::string_view> lines;
  const auto [first, last] = request.equal_range(http::field::sec_websocket_protocol);
  for (auto it = first; it != last; ++it) lines.push_back(view(it->value()));
  return lines;
}

std::string machine_name() {
  char name[256] = {};
  return ::gethostname(name, sizeof name - 1) == 0 ? std::string(name) : std::string();
}

// Descriptors kept free for what is not a connection: SIM regions of the pumps and the page,
// the listening socket, the standard streams.
constexpr rlim_t kReservedDescriptors = 64;
// Connections over the limit that still get a 503 sentence; beyond them they are closed at once.
constexpr unsigned kRefusalSlots = 32;

// The connection limit the process can keep: the option, lowered to what RLIMIT_NOFILE leaves.
unsigned connection_limit(unsigned wanted) {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return wanted;
  const rlim_t usable = limit.rlim_cur > kReservedDescriptors + kRefusalSlots + 1
                            ? limit.rlim_cur - kReservedDescriptors - kRefusalSlots
                            : 1;
  return static_cast<unsigned>(std::min<rlim_t>(std::max(wanted, 1u), usable));
}

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
                [this](const CatalogChanges& changes) { hub.update(changes); },
                [this] { after_poll(); }),
        access(o.allowed_origins, machine_name()),
        acceptor(ioc),
        accept_backoff(ioc),
        max_connections(connection_limit(o.max_connections)) {
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
  void admit(tcp::socket socket);
  void stop();

  // Counts a connection while it lives (an HTTP or WebSocket session holds it).
  std::shared_ptr<void> count_connection() {
    ++connections;
    return std::shared_ptr<void>(nullptr, [this](void*) { --connections; });
  }

  ServerOptions options;
  SessionOptions session;
  Hub hub;
  PageFrames frames;
  Catalog catalog;
  AccessPolicy access;
  // Declared after the hub: destroyed first, so sessions never outlive the hub they refer to.
  net::io_context ioc;
  tcp::acceptor acceptor;
  net::steady_timer accept_backoff;
  const unsigned max_connections;
  std::atomic<unsigned> connections{0};
  std::atomic<std::uint64_t> accept_failures{0};
  std::vector<std::thread> threads;
  bool stopped = false;
  // Declared last: destroyed (joined) first, while everything its jobs use still exists.
  RenderWorker renderer;
};

namespace {

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  // `refuse`: the server is at its connection limit; the request is answered with 503.
  HttpSession(tcp::socket&& socket, Server::Impl& server, std::shared_ptr<void> connection,
              bool refuse)
      : stream_(std::move(socket)),
        server_(server),
        connection_(std::move(connection)),
        refuse_(refuse) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(16 * 1024);
    parser_->body_limit(16 * 1024);
    stream_.expires_after(refuse_ ? 5s : 30s);  // a client that sends nothing is dropped
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
    if (refuse_) {
      return reply_error(http::status::service_unavailable,
                         "sim_foxglove serves " + std::to_string(server_.max_connections) +
                             " connections at once and has that many; close a page or client "
                             "(or raise --max-connections) and retry.",
                         request.version(), false);
    }
    const std::string_view host = view(request[http::field::host]);
    if (auto problem = server_.access.host_problem(host); !problem.empty()) {
      return reply_error(http::status::forbidden, std::move(problem), request.version(), false);
    }
    if (websocket::is_upgrade(request)) return upgrade(std::move(request), host);
    respond(request);
  }

  void upgrade(http::request<http::string_body> request, std::string_view host) {
    const auto subprotocol = choose_subprotocol(subprotocol_lines(request));
    if (!subprotocol) {
      return reply_error(http::status::bad_request,
                         "This server speaks the Foxglove WebSocket protocol: connect with the "
                         "subprotocol foxglove.sdk.v1 or foxglove.websocket.v1 (Foxglove or "
                         "Lichtblick does).",
                         request.version(), false);
    }
    const std::string_view origin = view(request[http::field::origin]);
    if (auto problem = server_.access.origin_problem(origin, host); !problem.empty()) {
      return reply_error(http::status::forbidden, std::move(problem), request.version(), false);
    }
    start_ws_session(stream_.release_socket(), std::move(request), server_.hub, server_.session,
                     *subprotocol, std::move(connection_));
  }

  void respond(const http::request<http::string_body>& request) {
    const unsigned version = request.version();
    const bool keep_alive = request.keep_alive();
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      return reply_error(http::status::method_not_allowed, "Only GET is served here.", version,
                         keep_alive);
    }
    auto target = parse_target(view(request.target()));
    if (!target) {
      return reply_error(http::status::bad_request,
                         "The address is malformed; open / for the page.", version, keep_alive);
    }
    if (target->path == "/" || target->path == "/index.html") {
      return reply("text/html; charset=utf-8", std::string(kPageHtml), version, keep_alive,
                   request.method() == http::verb::head);
    }
    if (target->path == "/api/streams") {
      return reply("application/json",
                   streams_json(server_.catalog.snapshot(), server_.catalog.mountings()), version,
                   keep_alive, request.method() == http::verb::head);
    }
    if (target->path == "/api/image" || target->path == "/api/topdown") {
      return render(std::move(*target), version, keep_alive, request.method() == http::verb::head);
    }
    reply_error(http::status::not_found, "Nothing here; open / for the page.", version,
                keep_alive);
  }

  // /api/image and /api/topdown: the picture is made on the render worker, never on this io
  // thread (which also writes Foxglove clients' frames); the answer is written back on this
  // connection's strand. A full queue is answered at once: 503, try again in a second.
  void render(Target target, unsigned version, bool keep_alive, bool head) {
    const auto stream = target.query.find("stream");
    if (stream == target.query.end() || !server_.catalog.find(stream->second)) {
      return reply_error(http::status::not_found,
                         "No such stream here; /api/streams lists the streams.", version,
                         keep_alive);
    }
    auto job = [self = shared_from_this(), target = std::move(target), version, keep_alive, head] {
      Expected<Picture> picture = self->make_picture(target);
      net::post(self->stream_.get_executor(),
                [self, picture = std::move(picture), version, keep_alive, head]() mutable {
                  if (!picture) {
                    return self->reply_error(http::status::service_unavailable,
                                             picture.error().message, version, keep_alive);
                  }
                  self->reply_bytes("image/jpeg", *picture, version, keep_alive, head);
                });
    };
    if (!server_.renderer.try_post(std::move(job))) {
      reply_error(http::status::service_unavailable,
                  "The page's pictures are being made for other requests; retry in a second.",
                  version, keep_alive, /*retry_after_s=*/1);
    }
  }

  // On the render worker: the picture the target asks for (it names a stream that exists).
  Expected<Picture> make_picture(const Target& target) {
    const std::string& stream = target.query.at("stream");
    if (const auto lidar = target.query.find("lidar"); lidar != target.query.end()) {
      return projection(stream, lidar->second);
    }
    if (target.path == "/api/image") return server_.frames.image(stream);
    TopDownOptions options;
    if (const auto c = target.query.find("color"); c != target.query.end()) {
      options.color = c->second == "intensity" ? ColorBy::intensity : ColorBy::height;
    }
    if (const auto r = target.query.find("range"); r != target.query.end()) {
      char* end = nullptr;
      const float range = std::strtof(r->second.c_str(), &end);
      if (end != r->second.c_str() && range >= 1.0f && range <= 1000.0f) options.range_m = range;
    }
    return server_.frames.top_down(stream, options);
  }

  // /api/image?stream=CAMERA&lidar=LIDAR: the LiDAR's points drawn into the camera's image,
  // through the calibration and mountings the streams describe.
  Expected<Picture> projection(const std::string& camera, const std::string& lidar) {
    const auto c = server_.catalog.find(camera);
    const auto l = server_.catalog.find(lidar);
    if (!l || lidar == camera) {
      return Error{ErrorCode::not_found, "No LiDAR stream " + lidar + " here; /api/streams lists them."};
    }
    const std::optional<SensorInfo> camera_sensor = c && c->status ? c->status->sensor : std::nullopt;
    if (!camera_sensor || !camera_sensor->calibration) {
      return Error{ErrorCode::not_found, camera + " has no calibration; start its writer with one "
                                                  "(--camera-info FILE) to draw points into it."};
    }
    auto pose = pose_between(server_.catalog.mountings(),
                                   frame_of(lidar, l->status ? l->status->sensor : std::nullopt),
                                   frame_of(camera, camera_sensor));
    if (!pose) return pose.error();
    return server_.frames.projection(camera, lidar, *pose, *camera_sensor->calibration);
  }

  // An answer: its header, and the body it holds until the write completes (text or a picture).
  struct Answer {
    Answer(http::status status, unsigned version, const char* type) : response(status, version) {
      response.set(http::field::server, "sim_foxglove");
      response.set(http::field::content_type, type);
    }
    http::response<http::empty_body> response;  // the header (the body is below)
    std::string head;                             // the header as sent
    std::string text;
    Jpeg picture;
  };

  void reply(const char* type, std::string body, unsigned version, bool keep_alive,
             bool head = false) {
    auto answer = std::make_shared<Answer>(http::status::ok, version, type);
    answer->response.set(http::field::cache_control, "no-store");
    answer->response.keep_alive(keep_alive);
    answer->text = std::move(body);
    send(answer, answer->text.data(), answer->text.size(), head, keep_alive);
  }

  void reply_bytes(const char* type, const Picture& picture, unsigned version, bool keep_alive,
                   bool head) {
    auto answer = std::make_shared<Answer>(http::status::ok, version, type);
    answer->response.set(http::field::cache_control, "no-store");
    answer->response.keep_alive(keep_alive);
    answer->response.set("X-Sim-View", picture.caption);
    answer->picture = picture.jpeg;
    send(answer, answer->picture->data(), answer->picture->size(), head, keep_alive);
  }

  void reply_error(http::status status, std::string sentence, unsigned version, bool keep_alive,
                   unsigned retry_after_s = 0) {
    auto answer = std::make_shared<Answer>(status, version, "text/plain; charset=utf-8");
    if (retry_after_s > 0) {
      answer->response.set(http::field::retry_after, std::to_string(retry_after_s));
    }
    answer->response.keep_alive(keep_alive);
    answer->text = std::move(sentence) + "\n";
    send(answer, answer->text.data(), answer->text.size(), false, keep_alive);
  }

  // `body`: `size` bytes the answer holds; a HEAD answer has their length and not them.
  // Why not http::async_write: Beast's serializer and its write operations were most of this
  // file's compile (docs/build-times.md). The bytes are the same: the serializer sends the header
  // its fields writer formats, then a Content-Length body as it is.
  void send(const std::shared_ptr<Answer>& answer, const void* body, std::size_t size, bool head,
            bool keep_alive) {
    answer->response.content_length(size);  // what prepare_payload() sets for these answers
    const http::response_header<>& header = answer->response.base();
    http::fields::writer formatted(header, header.version(), header.result_int());
    answer->head = beast::buffers_to_string(formatted.get());
    const std::array<net::const_buffer, 2> bytes{net::buffer(answer->head),
                                                 net::const_buffer(body, head ? 0 : size)};
    stream_.expires_after(30s);
    net::async_write(stream_, bytes,
                     [self = shared_from_this(), answer, keep_alive](beast::error_code ec,
                                                                     std::size_t) {
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
  std::shared_ptr<void> connection_;  // counted while this session (or its WebSocket) lives
  const bool refuse_;
};

}  // namespace

void Server::Impl::accept() {
  acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
    if (!ec) {
      admit(std::move(socket));
      return accept();
    }
    if (ec == net::error::connection_aborted) return accept();  // the peer gave up; next one
    // Out of descriptors or memory (EMFILE, ENFILE, ENOBUFS): trying again at once fails again
    // at once, a busy loop that serves nobody. Wait, while the connected clients are served.
    ++accept_failures;
    accept_backoff.expires_after(100ms);
    accept_backoff.async_wait([this](beast::error_code wait_ec) {
      if (!wait_ec && acceptor.is_open()) accept();
    });
  });
}

// Serves the connection, answers it 503 when the server is at its limit, or closes it at once
// when even the refusals are many (a flood must not take the descriptors the served need).
void Server::Impl::admit(tcp::socket socket) {
  const unsigned live = connections.load();
  if (live >= max_connections + kRefusalSlots) {
    beast::error_code ignored;
    socket.close(ignored);
    return;
  }
  std::make_shared<HttpSession>(std::move(socket), *this, count_connection(),
                                live >= max_connections)
      ->read();
}

void Server::Impl::stop() {
  if (stopped) return;
  stopped = true;
  catalog.stop();
  net::post(ioc, [this] {
    beast::error_code ignored;
    acceptor.close(ignored);
    accept_backoff.cancel();
  });
  ioc.stop();
  for (auto& t : threads) t.join();
  threads.clear();
  renderer.stop();  // a picture being made is finished; its answer is never written
  hub.stop();  // pumps end before the sessions they hold are destroyed with the io_context
}

Expected<Server> Server::start(const ServerOptions& options) {
  beast::error_code ec;
  const auto address = net::ip::make_address(options.bind, ec);
  if (ec) {
    return Error{ErrorCode::invalid_argument,
                 "--bind " + options.bind + " is not an IP address; use e.g. 127.0.0.1 or 0.0.0.0."};
  }
  if (options.max_rate_hz != 0 && !(options.max_rate_hz >= kMinRateHz)) {
    return Error{ErrorCode::invalid_argument,
                 "--max-rate must be 0 (every frame) or at least 0.000001 messages per second."};
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

std::uint64_t Server::accept_failures() const noexcept {
  return impl_ ? impl_->accept_failures.load() : 0;
}

void Server::stop() {
  if (impl_) impl_->stop();
}

}  // namespace sim::foxglove
