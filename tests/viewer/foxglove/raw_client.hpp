// SPDX-License-Identifier: Apache-2.0
// The tests' own client of sim_foxglove: a TCP connection to the server that speaks just enough
// HTTP and WebSocket to misbehave on purpose (unmasked frames, absurd lengths, floods) or to
// behave (subscribe, read message frames), plus the helpers the tests share. Every read gives up
// after kPatience, so a broken server fails a test instead of hanging it.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace sim_test_foxglove {

using namespace std::chrono_literals;

// Against hangs only: a test that reaches this has failed.
constexpr auto kPatience = 20s;

inline std::string unique_stream(const char* base) {
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
inline std::string host_port(const char* name, std::uint16_t port) {
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
  int fd() const { return fd_; }

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

  // The body that follows `head` (its Content-Length bytes), or nullopt.
  std::optional<std::string> read_body(const std::string& head) {
    const auto at = head.find("Content-Length: ");
    if (at == std::string::npos) return std::nullopt;
    std::string body(std::stoul(head.substr(at + 16)), '\0');
    if (!body.empty() && !read_exact(body.data(), body.size())) return std::nullopt;
    return body;
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

// {"op":"subscribe","subscriptions":[{"id":ID,"channelId":CHANNEL}]}, built in place (GCC 12
// at -O3 misreads "literal" + std::string&& as -Wrestrict).
inline std::string subscribe_request(std::uint32_t id, std::uint32_t channel) {
  std::string text = R"({"op":"subscribe","subscriptions":[{"id":)";
  text += std::to_string(id);
  text += R"(,"channelId":)";
  text += std::to_string(channel);
  text += "}]}";
  return text;
}

// A binary message-data frame's subscription id and timestamp (nullopt for anything else).
struct MessageData {
  std::uint32_t subscription_id = 0;
  std::uint64_t timestamp_ns = 0;
};
inline std::optional<MessageData> message_data(const Frame& f) {
  if (f.opcode != 0x2 || f.payload.size() < 13 || f.payload[0] != 0x01) return std::nullopt;
  auto byte = [&](std::size_t at) { return static_cast<unsigned char>(f.payload[at]); };
  MessageData m;
  for (int i = 3; i >= 0; --i) m.subscription_id = (m.subscription_id << 8) | byte(1 + i);
  for (int i = 7; i >= 0; --i) m.timestamp_ns = (m.timestamp_ns << 8) | byte(5 + i);
  return m;
}

}  // namespace sim_test_foxglove
