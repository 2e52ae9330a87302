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
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
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
    std::string request =
        "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n";
    if (with_subprotocol) request += "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n";
    request += "\r\n";
    if (!send_raw(request)) return std::nullopt;
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
    ASSERT_TRUE(client.send_raw("GET /etc/passwd HTTP/1.1\r\nHost: x\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 404 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("GET /api/image?stream=%2Fnot_a_stream HTTP/1.1\r\nHost: x\r\n\r\n"));
    const auto head = client.read_head();
    ASSERT_TRUE(head);
    EXPECT_NE(head->find(" 404 "), std::string::npos) << *head;
  }
  {
    RawClient client(port());
    ASSERT_TRUE(client.send_raw("GET /api/image?stream=%ZZ HTTP/1.1\r\nHost: x\r\n\r\n"));
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

}  // namespace
