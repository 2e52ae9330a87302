// SPDX-License-Identifier: Apache-2.0
// sim_foxglove against clients that misbehave, over raw TCP on loopback: malformed WebSocket
// frames, handshakes without the protocol, unknown ops, subscriptions to channels that do not
// exist, floods of requests from a client that does not read, a client that never reads its
// frames, garbage HTTP. Each gets an error status or a closed connection, and the server keeps
// serving the next client. The server runs in this process (the library), fed by a real SIM
// writer on a real shared-memory stream.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "sim/foxglove/server.hpp"
#include "sim/sim.hpp"

namespace {

using namespace std::chrono_literals;

// Against hangs only: a test that reaches this has failed.
constexpr auto kPatience = 20s;

std::string unique_stream(const char* base) {
  static std::atomic<int> counter{0};
  std::string name = "/";  // built in place: GCC 12 at -O3 misreads "/" + string (-Wrestrict)
  name += base;
  name += '_';
  name += std::to_string(getpid());
  name += '_';
  name += std::to_string(counter++);
  return name;
}

// "name:port", built in place (GCC 12 at -O3 misreads "literal" + std::string&& as -Wrestrict).
std::string host_port(const char* name, std::uint16_t port) {
  std::string text = name;
  text += ':';
  text += std::to_string(port);
  return text;
}

struct Frame {
  int opcode = -1;
  std::string payload;
};

// A TCP connection to the server that speaks just enough WebSocket to misbehave on purpose.
class RawClient {
 public:
  explicit RawClient(std::uint16_t port, int receive_buffer = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (receive_buffer > 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    }
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  bool connected() const { return connected_; }

  // False once the peer has closed or reset the connection.
  bool send_raw(const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, 10'000) <= 0) return false;  // the server stopped reading us
      const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

  // The HTTP response head (up to the blank line) or nullopt.
  std::optional<std::string> read_head() {
    std::string head;
    while (head.find("\r\n\r\n") == std::string::npos) {
      char c;
      if (!read_exact(&c, 1)) return std::nullopt;
      head += c;
    }
    return head;
  }

  // Sends the upgrade request; returns the response head.
  std::optional<std::string> handshake(bool with_subprotocol = true) {
    return handshake_with(with_subprotocol ? "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"
                                           : "");
  }
  // The upgrade request with these header lines (each ending in CRLF) and this Host.
  std::optional<std::string> handshake_with(const std::string& headers,
                                            const std::string& host = "127.0.0.1") {
    const std::string request =
        "GET / HTTP/1.1\r\nHost: " + host +
        "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n" +
        headers + "\r\n";
    if (!send_raw(request)) return std::nullopt;
    return read_head();
  }
  // A plain GET of `target` with this Host; returns the response head.
  std::optional<std::string> get(const std::string& target, const std::string& host = "127.0.0.1") {
    if (!send_raw("GET " + target + " HTTP/1.1\r\nHost: " + host + "\r\n\r\n")) return std::nullopt;
    return read_head();
  }

  // A client frame (masked, as RFC 6455 requires of clients unless `masked` is false).
  static std::string frame(int opcode, const std::string& payload, bool masked = true,
                           bool fin = true, std::uint8_t extra_bits = 0) {
    std::string out;
    out += static_cast<char>((fin ? 0x80 : 0) | extra_bits | opcode);
    const std::uint8_t mask_bit = masked ? 0x80 : 0;
    if (payload.size() < 126) {
      out += static_cast<char>(mask_bit | payload.size());
    } else if (payload.size() < 65536) {
      out += static_cast<char>(mask_bit | 126);
      out += static_cast<char>(payload.size() >> 8);
      out += static_cast<char>(payload.size() & 0xFF);
    } else {
      out += static_cast<char>(mask_bit | 127);
      for (int i = 7; i >= 0; --i) out += static_cast<char>((payload.size() >> (8 * i)) & 0xFF);
    }
    const char key[4] = {0x12, 0x34, 0x56, 0x78};
    if (masked) out.append(key, 4);
    for (std::size_t i = 0; i < payload.size(); ++i) {
      out += masked ? static_cast<char>(payload[i] ^ key[i % 4]) : payload[i];
    }
    return out;
  }
  bool send_text(const std::string& text) { return send_raw(frame(0x1, text)); }

  // The next server frame, or nullopt when the connection ended (or the patience ran out).
  std::optional<Frame> read_frame() {
    unsigned char h[2];
    if (!read_exact(h, 2)) return std::nullopt;
    std::uint64_t length = h[1] & 0x7F;
    if (length == 126) {
      unsigned char e[2];
      if (!read_exact(e, 2)) return std::nullopt;
      length = (std::uint64_t{e[0]} << 8) | e[1];
    } else if (length == 127) {
      unsigned char e[8];
      if (!read_exact(e, 8)) return std::nullopt;
      length = 0;
      for (unsigned char b : e) length = (length << 8) | b;
    }
    if (length > (64u << 20)) return std::nullopt;
    Frame f;
    f.opcode = h[0] & 0x0F;
    f.payload.resize(length);
    if (length > 0 && !read_exact(f.payload.data(), length)) return std::nullopt;
    return f;
  }

  // Reads text frames until one contains `needle`.
  std::optional<std::string> read_text_with(const std::string& needle) {
    while (auto f = read_frame()) {
      if (f->opcode == 0x1 && f->payload.find(needle) != std::string::npos) return f->payload;
      if (f->opcode == 0x8) return std::nullopt;
    }
    return std::nullopt;
  }

  // True when the server ends the connection: EOF, reset or a close frame, reading everything
  // it sent before.
  bool closed_by_server() {
    for (;;) {
      auto f = read_frame();
      if (!f) return !timed_out_;
      if (f->opcode == 0x8) return true;
    }
  }

 private:
  bool read_exact(void* out, std::size_t size) {
    auto* p = static_cast<char*>(out);
    const auto give_up = std::chrono::steady_clock::now() + kPatience;
    while (size > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          give_up - std::chrono::steady_clock::now());
      pollfd pfd{fd_, POLLIN, 0};
      if (left.count() <= 0 || ::poll(&pfd, 1, static_cast<int>(left.count())) <= 0) {
        timed_out_ = true;
        return false;
      }
      const ssize_t n = ::recv(fd_, p, size, 0);
      if (n <= 0) return false;
      p += n;
      size -= static_cast<std::size_t>(n);
    }
    return true;
  }

  int fd_ = -1;
  bool connected_ = false;
  bool timed_out_ = false;
};

// A SIM camera stream with a writer thread publishing frames until the fixture ends.
class FoxgloveBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    stream_ = unique_stream("fox_bad");
    auto writer = sim::Writer::create(
        {.name = stream_,
         .layout = sim::Layout::of(sim::ImageLayout::packed(640, 480, sim::PixelFormat::bgr8))});
    ASSERT_TRUE(writer) << writer.error().message;
    writer_thread_ = std::thread([this, w = std::move(writer.value())]() mutable {
      std::vector<std::byte> frame(640 * 480 * 3, std::byte{0x40});
      while (!stop_.load()) {
        frame[0] = std::byte(published_.load() & 0xFF);
        (void)w.write(frame, sim::realtime_ns());
        published_.fetch_add(1);
        std::this_thread::sleep_for(10ms);
      }
    });
    sim::foxglove::ServerOptions options;
    options.port = 0;
    options.streams = {stream_};
    options.poll_interval = 100ms;
    options.send_timeout = 1000ms;
    auto server = sim::foxglove::Server::start(options);
    ASSERT_TRUE(server) << server.error().message;
    server_.emplace(std::move(server.value()));
  }
  void TearDown() override {
    if (server_) server_->stop();
    stop_.store(true);
    if (writer_thread_.joinable()) writer_thread_.join();
    (void)sim::destroy(stream_, true);
  }

  std::uint16_t port() const { return server_->port(); }

  // Another server on the fixture's stream, with options of the test's own.
  sim::foxglove::Server another_server(sim::foxglove::ServerOptions options) {
    options.port = 0;
    options.streams = {stream_};
    auto server = sim::foxglove::Server::start(options);
    EXPECT_TRUE(server) << server.error().message;
    return std::move(server.value());
  }

  // Subscribes the client to `channel` (subscription id 7).
  static void subscribe(RawClient& client, std::uint32_t channel) {
    ASSERT_TRUE(client.send_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":)" +
                                 std::to_string(channel) + "}]}"));
  }

  // Reads until a message frame stamped after `after_ns` arrives: one published meanwhile.
  static bool receives_frame_after(RawClient& client, std::int64_t after_ns) {
    while (auto f = client.read_frame()) {
      if (f->opcode != 0x2 || f->payload.size() < 13) continue;
      std::uint64_t stamp = 0;
      for (int i = 7; i >= 0; --i) stamp = (stamp << 8) | static_cast<unsigned char>(f->payload[5 + i]);
      if (static_cast<std::int64_t>(stamp) > after_ns) return true;
    }
    return false;
  }

  // A client past the handshake that has read serverInfo and the advertise of our stream;
  // returns the stream's channel id.
  std::uint32_t open_client(RawClient& client) {
    EXPECT_TRUE(client.connected());
    const auto head = client.handshake();
    EXPECT_TRUE(head && head->find(" 101 ") != std::string::npos) << head.value_or("(none)");
    EXPECT_NE(head->find("foxglove.websocket.v1"), std::string::npos);
    EXPECT_TRUE(client.read_text_with("\"serverInfo\""));
    const auto advertise = client.read_text_with(stream_);
    EXPECT_TRUE(advertise) << "the stream was never advertised";
    if (!advertise) return 0;
    const auto at = advertise->find("\"id\":");
    return static_cast<std::uint32_t>(std::stoul(advertise->substr(at + 5)));
  }

  // A well-behaved client still gets served: the server survived what came before.
  void expect_server_still_serves() {
    RawClient client(port());
    const std::uint32_t channel = open_client(client);
    ASSERT_TRUE(client.send_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":)" +
                                 std::to_string(channel) + "}]}"));
    for (;;) {
      auto f = client.read_frame();
      ASSERT_TRUE(f) << "no message frame arrived";
      if (f->opcode == 0x2) {
        ASSERT_GT(f->payload.size(), 13u);
        EXPECT_EQ(f->payload[0], 0x01);  // message data
        EXPECT_EQ(f->payload[1], 7);     // our subscription id, little endian
        return;
      }
    }
  }

  std::string stream_;
  std::optional<sim::foxglove::Server> server_;
  std::thread writer_thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> published_{0};
};

TEST_F(FoxgloveBadInput, AnUnmaskedClientFrameClosesThatConnectionOnly) {
  RawClient client(port());
  open_client(client);
  ASSERT_TRUE(client.send_raw(RawClient::frame(0x1, R"({"op":"subscribe"})", /*masked=*/false)));
  EXPECT_TRUE(client.closed_by_server());
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, ReservedBitsUnknownOpcodesAndBadUtf8CloseTheConnection) {
  {
    RawClient client(port());
    open_client(client);
    ASSERT_TRUE(client.send_raw(RawClient::frame(0x1, "{}", true, true, /*RSV1..3=*/0x70)));
    EXPECT_TRUE(client.closed_by_server());
  }
  {
    RawClient client(port());
    open_client(client);
    ASSERT_TRUE(client.send_raw(RawClient::frame(0x3, "what is this")));  // reserved opcode
    EXPECT_TRUE(client.closed_by_server());
  }
  {
    RawClient client(port());
    open_client(client);
    // A text frame that is not UTF-8 (RFC 6455 asks to fail the connection, code 1007).
    ASSERT_TRUE(client.send_raw(RawClient::frame(0x1, "{\"op\":\"\xff\xfe\"}")));
    EXPECT_TRUE(client.closed_by_server());
  }
  {
    RawClient client(port());
    open_client(client);
    // A continuation frame with no message to continue.
    ASSERT_TRUE(client.send_raw(RawClient::frame(0x0, "dangling")));
    EXPECT_TRUE(client.closed_by_server());
  }
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, AnAbsurdFrameLengthClosesTheConnectionWithoutAllocatingIt) {
  RawClient client(port());
  open_client(client);
  // Header of a text frame that claims 2^62 bytes, then a few bytes of it.
  std::string header;
  header += static_cast<char>(0x81);
  header += static_cast<char>(0x80 | 127);
  header += std::string("\x40\x00\x00\x00\x00\x00\x00\x00", 8);
  header += std::string("\x01\x02\x03\x04", 4);
  ASSERT_TRUE(client.send_raw(header + "abcd"));
  EXPECT_TRUE(client.closed_by_server());
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, AMessageLargerThanAnyRequestClosesTheConnection) {
  RawClient client(port());
  open_client(client);
  const std::string huge = R"({"op":"subscribe","pad":")" + std::string(200'000, 'x') + "\"}";
  client.send_raw(RawClient::frame(0x1, huge));  // the server may close before all of it is sent
  EXPECT_TRUE(client.closed_by_server());
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, BadRequestsGetAnErrorStatusAndTheConnectionStaysUsable) {
  RawClient client(port());
  const std::uint32_t channel = open_client(client);
  const std::pair<std::string, std::string> cases[] = {
      {"this is not json", "not valid JSON"},
      {"[1,2,3]", "no \\\"op\\\""},
      {R"({"op":"launchRockets"})", "unknown op"},
      {R"({"op":"getParameters","parameterNames":[]})", "not offered"},
      {R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":424242}]})", "424242"},
      {R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})", "integer"},
      {R"({"op":"subscribe","subscriptions":"all"})", "subscriptions"},
      {R"({"op":"unsubscribe","subscriptionIds":[99]})", "not active"},
  };
  for (const auto& [request, expected] : cases) {
    ASSERT_TRUE(client.send_text(request)) << request;
    const auto status = client.read_text_with("\"status\"");
    ASSERT_TRUE(status) << "no status for " << request;
    EXPECT_NE(status->find(expected), std::string::npos) << *status;
  }
  // A binary message (client publish, which this server does not offer).
  ASSERT_TRUE(client.send_raw(RawClient::frame(0x2, std::string("\x01\x00\x00\x00", 4))));
  EXPECT_TRUE(client.read_text_with("client publish"));
  // Subscribing twice to one channel, or reusing an id, is refused; the first still works.
  const std::string subscribe = R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":)" +
                                std::to_string(channel) + "}]}";
  ASSERT_TRUE(client.send_text(subscribe));
  ASSERT_TRUE(client.send_text(subscribe));
  EXPECT_TRUE(client.read_text_with("already"));
  for (;;) {
    auto f = client.read_frame();
    ASSERT_TRUE(f);
    if (f->opcode == 0x2) break;  // the first subscription delivers
  }
}

TEST_F(FoxgloveBadInput, AHandshakeWithoutTheFoxgloveSubprotocolIsRefusedWithASentence) {
  RawClient client(port());
  const auto head = client.handshake(/*with_subprotocol=*/false);
  ASSERT_TRUE(head);
  EXPECT_NE(head->find(" 400 "), std::string::npos) << *head;
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, GarbageHttpGetsA400AndUnknownPathsA404) {
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("\x16\x03\x01 this is TLS, not HTTP\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 400 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("GET /etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 404 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("GET /api/image?stream=%2Fnot_a_stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 404 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("GET /api/image?stream=%ZZ HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 400 "), std::string::npos) << *head;
  }
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, AFloodOfRequestsFromAClientThatDoesNotReadIsCutOff) {
  RawClient client(port(), /*receive_buffer=*/4096);
  const std::uint32_t channel = open_client(client);
  // Each pair makes a subscription and ends it; each bad op earns a status nobody reads. The
  // server must neither grow without bound nor stall: it closes this client.
  const std::string pair =
      RawClient::frame(0x1, R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":)" +
                                std::to_string(channel) + "}]}") +
      RawClient::frame(0x1, R"({"op":"unsubscribe","subscriptionIds":[1]})") +
      RawClient::frame(0x1, R"({"op":"nonsense"})");
  int sent = 0;
  while (sent < 200'000 && client.send_raw(pair)) ++sent;
  EXPECT_TRUE(client.closed_by_server()) << "after " << sent << " request triples";
  expect_server_still_serves();
}

TEST_F(FoxgloveBadInput, AClientThatNeverReadsIsClosedAndOthersKeepGettingFrames) {
  RawClient stuck(port(), /*receive_buffer=*/4096);
  const std::uint32_t channel = open_client(stuck);
  ASSERT_TRUE(stuck.send_text(R"({"op":"subscribe","subscriptions":[{"id":3,"channelId":)" +
                              std::to_string(channel) + "}]}"));
  // Meanwhile another client is served, and the SIM writer keeps publishing.
  expect_server_still_serves();
  const std::uint64_t before = published_.load();
  // The stuck client's 900 KB frames cannot be delivered; once a write has waited longer than
  // the send timeout (1 s here) the server closes it. Reading earlier would unblock the server,
  // so the test first lets that happen, then drains what fitted in the buffers up to the end.
  std::this_thread::sleep_for(5s);
  EXPECT_TRUE(stuck.closed_by_server());
  EXPECT_GT(published_.load(), before) << "the writer stopped publishing";
}

// Review M1: Foxglove's current apps offer only foxglove.sdk.v1; RFC 6455 lets a client list its
// subprotocols on several header lines. The answer names the one the client offered.
TEST_F(FoxgloveBadInput, ASdkClientGetsTheSubprotocolItOfferedAlsoOnASecondHeaderLine) {
  {
    RawClient client(port());
    const auto head = client.handshake_with("Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n");
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 101 "), std::string::npos) << *head;
    EXPECT_NE(head->find("Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n"), std::string::npos) << *head;
    EXPECT_TRUE(client.read_text_with("\"serverInfo\""));
  }
  {
    RawClient client(port());
    const auto head = client.handshake_with(
        "Sec-WebSocket-Protocol: chat\r\nSec-WebSocket-Protocol: foxglove.websocket.v1\r\n");
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 101 "), std::string::npos) << *head;
    EXPECT_NE(head->find("Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n"), std::string::npos)
        << *head;
  }
  expect_server_still_serves();
}

// Review M2: WebSockets are not covered by CORS, so the server checks Origin itself; a page of
// another site gets 403 and a sentence, the server's own page and Foxglove's web app get in.
TEST_F(FoxgloveBadInput, APageOfAnotherSiteMayNotOpenTheWebSocket) {
  const std::string offer = "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n";
  {
    RawClient client(port());
    const auto head = client.handshake_with(offer + "Origin: https://evil.example\r\n");
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 403 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());  // another local page, on another port, is another site too
    const auto head = client.handshake_with(offer + "Origin: http://127.0.0.1:1\r\n",
                                            host_port("127.0.0.1", port()));
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 403 "), std::string::npos) << *head;
  }
  const std::string own = host_port("127.0.0.1", port());
  for (const std::string& origin : {"http://" + own, std::string("https://app.foxglove.dev")}) {
    RawClient client(port());
    const auto head = client.handshake_with(offer + "Origin: " + origin + "\r\n", own);
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 101 "), std::string::npos) << origin << ": " << *head;
  }
  expect_server_still_serves();
}

// Review M2: DNS rebinding (a name of the attacker's resolving to this machine) is refused by
// the Host check; IP addresses and localhost are served.
TEST_F(FoxgloveBadInput, ARequestNamingAnotherHostIsRefused) {
  {
    RawClient client(port());
    const auto head = client.get("/api/streams", host_port("attacker.example", port()));
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 403 "), std::string::npos) << *head;
  }
  for (const std::string& host : {std::string("127.0.0.1"), host_port("localhost", port())}) {
    RawClient client(port());
    const auto head = client.get("/api/streams", host);
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 200 "), std::string::npos) << host << ": " << *head;
  }
}

TEST_F(FoxgloveBadInput, AnAllowedOriginOpensTheWebSocketAndItsHostReadsThePage) {
  sim::foxglove::ServerOptions options;
  options.allowed_origins = {"http://viewer.example:9000"};
  auto server = another_server(options);
  {
    RawClient client(server.port());
    const auto head = client.handshake_with(
        "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\nOrigin: http://viewer.example:9000\r\n",
        host_port("viewer.example", server.port()));
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 101 "), std::string::npos) << *head;
  }
  RawClient client(server.port());
  const auto head = client.get("/api/streams", "viewer.example");
  ASSERT_TRUE(head);
  EXPECT_NE(head->find(" 200 "), std::string::npos) << *head;
}

// Review H1: connections beyond --max-connections are answered 503 with a sentence (not left to
// exhaust the descriptors); the connected client keeps getting frames; a freed place is reused.
TEST_F(FoxgloveBadInput, ConnectionsBeyondTheLimitGetA503AndTheConnectedAreStillServed) {
  sim::foxglove::ServerOptions options;
  options.max_connections = 3;
  auto server = another_server(options);
  RawClient viewer(server.port());
  subscribe(viewer, open_client(viewer));
  std::optional<RawClient> idle1(std::in_place, server.port());
  std::optional<RawClient> idle2(std::in_place, server.port());
  ASSERT_TRUE(idle1->connected() && idle2->connected());
  {
    RawClient extra(server.port());
    const auto head = extra.get("/api/streams");
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 503 "), std::string::npos) << *head;
  }
  EXPECT_TRUE(receives_frame_after(viewer, sim::realtime_ns())) << "the connected client starved";
  idle1.reset();
  idle2.reset();
  // The server notices the closed connections when it reads them; until then it says 503.
  const auto give_up = std::chrono::steady_clock::now() + kPatience;
  std::string last;
  while (std::chrono::steady_clock::now() < give_up) {
    RawClient next(server.port());
    last = next.get("/api/streams").value_or("(no answer)");
    if (last.find(" 200 ") != std::string::npos) break;
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_NE(last.find(" 200 "), std::string::npos) << last;
}

// Review H1: out of file descriptors, accept() fails at once every time; the server must wait
// between tries (at most one failure per 100 ms backoff) instead of spinning a core, keep
// serving the connected client, and accept the waiting connection once descriptors are free.
TEST_F(FoxgloveBadInput, OutOfDescriptorsTheServerWaitsInsteadOfSpinningAndRecovers) {
  sim::foxglove::ServerOptions options;
  options.poll_interval = std::chrono::hours(1);  // the catalog would fail to open regions too
  auto server = another_server(options);
  RawClient viewer(server.port());
  subscribe(viewer, open_client(viewer));
  ASSERT_TRUE(receives_frame_after(viewer, 0));

  // A client socket made now (it needs a descriptor), connected once the table is full.
  const int waiting = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(waiting, 0);
  rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &saved), 0);
  int highest = waiting;
  for (int fd = 0; fd < 65536 && fd < static_cast<int>(std::min<rlim_t>(saved.rlim_cur, 65536)); ++fd) {
    if (::fcntl(fd, F_GETFD) != -1) highest = fd;
  }
  rlimit low = saved;
  low.rlim_cur = static_cast<rlim_t>(highest) + 16;
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
  std::vector<int> fillers;
  for (int fd; (fd = ::dup(0)) >= 0;) fillers.push_back(fd);
  ASSERT_EQ(errno, EMFILE);

  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(server.port());
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const auto full_since = std::chrono::steady_clock::now();
  const std::int64_t full_since_ns = sim::realtime_ns();
  ASSERT_EQ(::connect(waiting, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  std::this_thread::sleep_for(1s);
  const std::uint64_t failures = server.accept_failures();
  const auto full_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                           std::chrono::steady_clock::now() - full_since)
                           .count();
  const bool served_meanwhile = receives_frame_after(viewer, full_since_ns);

  for (const int fd : fillers) ::close(fd);
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &saved), 0);
  EXPECT_GE(failures, 1u) << "the descriptor table was never full for the server";
  EXPECT_LE(failures, static_cast<std::uint64_t>(full_ms / 100 + 2))
      << "accept() failed " << failures << " times in " << full_ms << " ms: the loop spins";
  EXPECT_TRUE(served_meanwhile) << "the connected client got no frame while descriptors were out";

  const std::string get = "GET /api/streams HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  ASSERT_EQ(::send(waiting, get.data(), get.size(), MSG_NOSIGNAL), static_cast<ssize_t>(get.size()));
  pollfd p{waiting, POLLIN, 0};
  char answer[16] = {};
  ASSERT_EQ(::poll(&p, 1, 20'000), 1) << "the waiting connection was never accepted";
  ASSERT_GT(::recv(waiting, answer, sizeof answer - 1, 0), 0);
  EXPECT_EQ(std::string(answer).substr(0, 12), "HTTP/1.1 200");
  ::close(waiting);
}

// Review L1: a request naming many bad ids earns one status that lists them (not one status per
// id, which overflowed the 256-text queue of a client that reads everything and closed it).
TEST_F(FoxgloveBadInput, ARequestWithManyBadIdsGetsOneStatusAndTheConnectionStaysOpen) {
  RawClient client(port());
  const std::uint32_t channel = open_client(client);
  std::string subscriptions, ids;
  for (int i = 0; i < 300; ++i) {
    if (i > 0) subscriptions += ',';
    subscriptions += R"({"id":)";
    subscriptions += std::to_string(1000 + i);
    subscriptions += R"(,"channelId":)";
    subscriptions += std::to_string(500000 + i);
    subscriptions += '}';
  }
  for (int i = 0; i < 1024; ++i) {
    if (i > 0) ids += ',';
    ids += std::to_string(90000 + i);
  }
  ASSERT_TRUE(client.send_text(R"({"op":"subscribe","subscriptions":[)" + subscriptions + "]}"));
  const auto subscribed = client.read_text_with("\"status\"");
  ASSERT_TRUE(subscribed) << "the client was closed";
  EXPECT_NE(subscribed->find("500000, 500001"), std::string::npos) << *subscribed;
  EXPECT_NE(subscribed->find("and 284 more"), std::string::npos) << *subscribed;
  ASSERT_TRUE(client.send_text(R"({"op":"unsubscribe","subscriptionIds":[)" + ids + "]}"));
  const auto unsubscribed = client.read_text_with("\"status\"");
  ASSERT_TRUE(unsubscribed) << "the client was closed";
  EXPECT_NE(unsubscribed->find("and 1008 more"), std::string::npos) << *unsubscribed;
  // Still open and usable: the next frame of a real subscription arrives.
  subscribe(client, channel);
  EXPECT_TRUE(receives_frame_after(client, 0));
}

// Review L3: a rate below 1e-6 Hz would overflow the interval in nanoseconds (and then send
// every frame); it is refused with a sentence.
TEST_F(FoxgloveBadInput, AMaxRateTooSmallToMeanAnythingIsRefused) {
  for (const double rate : {1e-12, -1.0}) {
    sim::foxglove::ServerOptions options;
    options.port = 0;
    options.max_rate_hz = rate;
    const auto server = sim::foxglove::Server::start(options);
    ASSERT_FALSE(server) << rate;
    EXPECT_NE(server.error().message.find("--max-rate"), std::string::npos);
  }
}

}  // namespace
