// SPDX-License-Identifier: Apache-2.0
// sim_foxglove against clients that misbehave, over raw TCP on loopback: malformed WebSocket
// frames, handshakes without the protocol, unknown ops, subscriptions to channels that do not
// exist, floods of requests from a client that does not read, a client that never reads its
// frames, garbage HTTP. Each gets an error status or a closed connection, and the server keeps
// serving the next client. The server runs in this process (the library), fed by a real SIM
// writer on a real shared-memory stream.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "raw_client.hpp"
#include "sim/foxglove/server.hpp"
#include "sim/sim.hpp"

namespace {

using namespace sim_test_foxglove;

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
    ASSERT_TRUE(client.send_text(subscribe_request(7, channel)));
  }

  // Reads until a message frame stamped after `after_ns` arrives: one published meanwhile.
  static bool receives_frame_after(RawClient& client, std::int64_t after_ns) {
    while (auto f = client.read_frame()) {
      const auto message = message_data(*f);
      if (message && static_cast<std::int64_t>(message->timestamp_ns) > after_ns) return true;
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
    ASSERT_TRUE(client.send_text(subscribe_request(7, channel)));
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
  const std::string subscribe = subscribe_request(5, channel);
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
      RawClient::frame(0x1, subscribe_request(1, channel)) +
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
  ASSERT_TRUE(stuck.send_text(subscribe_request(3, channel)));
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
  // file:// is what desktop apps send (the docs let them in; issue 32: it got 403).
  for (const std::string& origin : {"http://" + own, std::string("https://app.foxglove.dev"),
                                    std::string("file://")}) {
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
  options.allowed_origins.push_back("http://viewer.example:9000");
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

// This process's descriptor table, full: the limit lowered to just above the highest
// descriptor in use, the rest taken by copies of stdin. release() (or the end) gives it back.
class FullDescriptorTable {
 public:
  FullDescriptorTable() {
    if (::getrlimit(RLIMIT_NOFILE, &saved_) != 0) return;
    int highest = 0;
    const int known = static_cast<int>(std::min<rlim_t>(saved_.rlim_cur, 65536));
    for (int fd = 0; fd < known; ++fd) {
      if (::fcntl(fd, F_GETFD) != -1) highest = fd;
    }
    rlimit low = saved_;
    low.rlim_cur = static_cast<rlim_t>(highest) + 16;
    if (::setrlimit(RLIMIT_NOFILE, &low) != 0) return;
    lowered_ = true;
    for (int fd; (fd = ::dup(0)) >= 0;) fillers_.push_back(fd);
    full_ = errno == EMFILE;
  }
  ~FullDescriptorTable() { release(); }
  FullDescriptorTable(const FullDescriptorTable&) = delete;
  FullDescriptorTable& operator=(const FullDescriptorTable&) = delete;

  bool full() const { return full_; }
  void release() {
    for (const int fd : fillers_) ::close(fd);
    fillers_.clear();
    if (lowered_) ::setrlimit(RLIMIT_NOFILE, &saved_);
    lowered_ = false;
  }

 private:
  rlimit saved_{};
  bool lowered_ = false;
  bool full_ = false;
  std::vector<int> fillers_;
};

bool connect_to_loopback(int fd, std::uint16_t port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
}

// The status line of the answer to a GET of /api/streams on a connected socket, or "".
std::string status_line_of_get(int fd) {
  const std::string get = "GET /api/streams HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  if (::send(fd, get.data(), get.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(get.size())) return "";
  pollfd p{fd, POLLIN, 0};
  char answer[16] = {};
  if (::poll(&p, 1, 20'000) != 1 || ::recv(fd, answer, sizeof answer - 1, 0) <= 0) return "";
  return std::string(answer).substr(0, 12);
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
  FullDescriptorTable table;
  ASSERT_TRUE(table.full());
  const auto full_since = std::chrono::steady_clock::now();
  const std::int64_t full_since_ns = sim::realtime_ns();
  ASSERT_TRUE(connect_to_loopback(waiting, server.port()));
  std::this_thread::sleep_for(1s);
  const std::uint64_t failures = server.accept_failures();
  const auto full_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                           std::chrono::steady_clock::now() - full_since)
                           .count();
  const bool served_meanwhile = receives_frame_after(viewer, full_since_ns);
  table.release();

  EXPECT_GE(failures, 1u) << "the descriptor table was never full for the server";
  EXPECT_LE(failures, static_cast<std::uint64_t>(full_ms / 100 + 2))
      << "accept() failed " << failures << " times in " << full_ms << " ms: the loop spins";
  EXPECT_TRUE(served_meanwhile) << "the connected client got no frame while descriptors were out";
  EXPECT_EQ(status_line_of_get(waiting), "HTTP/1.1 200") << "the waiting connection was not served";
  ::close(waiting);
}

// Review L6: a broken MJPEG frame (here only the start of a JPEG) is not served as a picture the
// browser shows as its broken-image icon; the page gets one sentence saying what is wrong.
TEST_F(FoxgloveBadInput, ABrokenMjpegFrameGetsASentenceInsteadOfAPicture) {
  const std::string camera = unique_stream("fox_mjpeg");
  auto writer = sim::Writer::create(
      {.name = camera,
       .capacity = 4096,
       .layout = sim::Layout::of(sim::ImageLayout{64, 48, 3, 0, sim::PixelFormat::mjpeg, 8})});
  ASSERT_TRUE(writer) << writer.error().message;
  const std::string start_of_a_jpeg = "\xFF\xD8\xFF\xE0 and then nothing a decoder can use";
  const auto bytes = std::as_bytes(std::span(start_of_a_jpeg));
  ASSERT_EQ(writer->write(bytes, sim::realtime_ns()), sim::WriteStatus::ok);
  sim::foxglove::ServerOptions options;
  options.port = 0;
  options.streams = {camera};
  auto server = sim::foxglove::Server::start(options);
  ASSERT_TRUE(server) << server.error().message;

  RawClient page(server->port());
  std::string target = "/api/image?stream=%2F";
  target += camera.substr(1);
  const auto head = page.get(target);
  ASSERT_TRUE(head);
  EXPECT_NE(head->find(" 503 "), std::string::npos) << *head;
  const auto sentence = page.read_body(*head);
  ASSERT_TRUE(sentence);
  EXPECT_NE(sentence->find("MJPEG frame cannot be shown"), std::string::npos) << *sentence;
  server->stop();
  (void)sim::destroy(camera, true);
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
